"""`bounce-gi`: render a .blend with Bounce GI, or compare it with a Cycles reference, from the command line.

Runs Blender as a Python module (bpy), so it works in background batch jobs. Bad input gives one line on stderr
and exit code 2; nothing is written unless the whole render succeeded.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile

EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 1
BLEND_MAGICS = (b"BLENDER", b"\x1f\x8b", b"\x28\xb5\x2f\xfd")  # plain, gzip, zstd-compressed .blend


class CliError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


def _progress(message: str) -> None:
    print(f"bounce-gi: {message}", file=sys.stderr, flush=True)


def check_blend_path(path: str) -> str:
    if not os.path.exists(path):
        raise CliError(f"{path}: no such file")
    if os.path.isdir(path):
        raise CliError(f"{path}: is a directory, not a .blend file")
    try:
        with open(path, "rb") as f:
            head = f.read(7)
    except OSError as exc:
        raise CliError(f"{path}: cannot read ({exc.strerror})") from None
    if not any(head.startswith(m) for m in BLEND_MAGICS):
        raise CliError(f"{path}: not a .blend file")
    return os.path.abspath(path)


def check_output_path(path: str, suffix: str) -> str:
    """Fail before rendering if the output cannot be written."""
    if not path.lower().endswith(suffix):
        raise CliError(f"{path}: output must be a {suffix} file")
    path = os.path.abspath(path)
    parent = os.path.dirname(path)
    if os.path.isdir(path):
        raise CliError(f"{path}: is a directory")
    if os.path.exists(parent) and not os.path.isdir(parent):
        raise CliError(f"{path}: {parent} is not a directory")
    if not os.path.isdir(parent):
        raise CliError(f"{path}: directory {parent} does not exist")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise CliError(f"{path}: not writable")
    # os.access() says yes to root even where nothing can be created (procfs, read-only mounts): try it.
    try:
        fd, probe = tempfile.mkstemp(prefix=".bounce-gi-probe-", dir=parent)
    except OSError as exc:
        raise CliError(f"{path}: not writable ({exc.strerror})") from None
    os.close(fd)
    os.unlink(probe)
    return path


def write_output(writer, path: str, *args) -> None:
    """Run an image writer; a failure (disk full, permissions changed meanwhile) is a one-line user error."""
    try:
        writer(path, *args)
    except OSError as exc:
        raise CliError(f"{path}: cannot write ({exc})") from None


def load_scene(path: str, resolution=None):
    """Open a .blend with bpy and extract its Scene; raise CliError for scenes that cannot be rendered."""
    import bpy

    from .extract import ExtractError, extract_scene

    path = check_blend_path(path)
    try:
        bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
    except RuntimeError as exc:
        raise CliError(f"{path}: Blender could not open it ({str(exc).strip().splitlines()[-1]})") from None
    try:
        scene = extract_scene(bpy.context.evaluated_depsgraph_get(), resolution)
    except ExtractError as exc:
        raise CliError(f"{path}: {exc}") from None
    if not scene.lights and not scene.has_emission():
        raise CliError(f"{path}: the scene has no lights and no emissive materials, so it would render black")
    if scene.triangle_count == 0:
        raise CliError(f"{path}: the scene has no visible geometry")
    return scene


def parse_method_options(pairs, settings_cls=None, flag: str = "--lpv") -> dict:
    """`--lpv key=value ...` (or `--vct ...`) → keyword arguments of the method's settings dataclass, typed like
    its fields."""
    import dataclasses

    if settings_cls is None:
        from ..gpu_kernels.lpv.settings import LpvSettings as settings_cls

    fields = {f.name: f for f in dataclasses.fields(settings_cls)}
    out = {}
    for pair in pairs or ():
        key, sep, value = pair.partition("=")
        if not sep or key not in fields:
            raise CliError(f"{flag} {pair}: expected KEY=VALUE with KEY one of {', '.join(fields)}")
        default = getattr(settings_cls(), key)
        try:
            if isinstance(default, bool):
                if value.lower() not in ("1", "0", "true", "false", "yes", "no", "on", "off"):
                    raise ValueError(value)
                out[key] = value.lower() in ("1", "true", "yes", "on")
            else:
                out[key] = type(default)(value)
        except (TypeError, ValueError):
            raise CliError(f"{flag} {pair}: {value!r} is not a valid {type(default).__name__}") from None
    return out


def vct_options(pairs) -> dict:
    from ..gpu_kernels.vct.settings import VctSettings

    return parse_method_options(pairs, VctSettings, "--vct")


def render_ours(scene, method: str, lpv_options: dict | None = None, vct_settings: dict | None = None):
    from ..gpu_kernels.engine import get_engine
    from ..gpu_kernels.gl.context import GpuUnavailableError
    from ..gpu_kernels.lpv.settings import LpvSettings
    from ..gpu_kernels.settings import RenderSettings, SceneError
    from ..gpu_kernels.vct.settings import VctSettings

    try:
        lpv_settings = LpvSettings(**(lpv_options or {}))
        vct = VctSettings(**(vct_settings or {}))
    except ValueError as exc:
        raise CliError(f"method settings: {exc}") from None
    settings = RenderSettings(method=method, width=scene.resolution[0], height=scene.resolution[1],
                              lpv=lpv_settings, vct=vct)
    try:
        return get_engine().render(scene, settings)
    except (SceneError, NotImplementedError, GpuUnavailableError) as exc:
        raise CliError(str(exc)) from None


def auto_quality(args) -> dict | None:
    """--budget-ms / --target-error: choose method and settings from the measured table (addon/quality.py);
    fills args.method, args.lpv, args.vct and returns what to report, or None when neither was given."""
    if args.budget_ms is None and args.target_error is None:
        return None
    from .quality import QualityError, choose, load_table

    if args.lpv or args.vct:
        raise CliError("--budget-ms/--target-error choose the method's settings; leave out --lpv/--vct")
    try:
        table = load_table()
        choice = choose(table, args.budget_ms, args.target_error, args.method)
    except QualityError as exc:
        raise CliError(str(exc)) from None
    args.method = choice.method
    import dataclasses

    from ..gpu_kernels.lpv.settings import LpvSettings
    from ..gpu_kernels.vct.settings import VctSettings

    cls = {"lpv": LpvSettings, "vct": VctSettings}.get(choice.method)
    known = {f.name for f in dataclasses.fields(cls)} if cls else set()
    pairs = [f"{k}={v}" for k, v in choice.settings.items() if k in known]  # a newer/older table's extra keys
    args.lpv, args.vct = (pairs, None) if choice.method == "lpv" else (None, pairs) if choice.method == "vct" \
        else (None, None)
    return {"method": choice.method, "settings": choice.settings, "measured_seconds": choice.seconds,
            "measured_rel_l1": choice.rel_l1, "message": choice.describe(table)}


def cmd_render(args) -> dict:
    quality = auto_quality(args)
    args.method = args.method or "none"
    if quality and not args.json:
        print(quality["message"])
    if args.out:
        out = check_output_path(args.out, ".exr")
    else:
        check_blend_path(args.scene)
        out = check_output_path(os.path.splitext(os.path.abspath(args.scene))[0] + f"_bounce_{args.method}.exr", ".exr")
    scene = load_scene(args.scene, tuple(args.res) if args.res else None)
    result = render_ours(scene, args.method, parse_method_options(args.lpv), vct_options(args.vct))
    from ..gpu_kernels.output import exr as exr_io

    write_output(exr_io.write_passes, out, result.passes)
    report = {"method": result.method, "resolution": list(result.resolution),
              "seconds": {k: round(v, 6) for k, v in result.timings.items()}, "skipped": result.skipped,
              "info": result.info,
              "scene": result.statistics, "warnings": result.warnings, "output": out}
    if quality:
        report["quality"] = quality
    if not args.json:
        print(format_timings(result.timings))
        for w in result.warnings:
            print(f"warning: {w}")
        print(f"wrote {out}")
    return report


def format_timings(timings: dict) -> str:
    lines = [f"{'pass':<16}{'ms':>10}"]
    for name, seconds in timings.items():
        if name != "total":
            lines.append(f"{name:<16}{seconds * 1000:>10.2f}")
    lines.append(f"{'total':<16}{timings.get('total', 0) * 1000:>10.2f}")
    return "\n".join(lines)


def compare(scene, method: str, samples: int, bounces: int = 8, progress=_progress, lpv_options=None,
            vct_settings=None) -> dict:
    """Render ours and the (cached) two-seed Cycles reference of the currently open scene; return the errors."""
    import numpy as np

    from ..gpu_kernels.output import metrics
    from .reference.cycles import ReferenceSettings, render_reference

    result = render_ours(scene, method, lpv_options, vct_settings)
    ref_settings = ReferenceSettings(scene.resolution[0], scene.resolution[1], samples=samples, bounces=bounces)
    ref = render_reference(scene.content_hash(), ref_settings, progress=progress)
    ours = result.passes
    mask = (ours["Position"].any(axis=-1) | (ours["Depth"][..., 0] < 1e9)) & (ref.passes["Depth"][..., 0] < 1e9)
    errors, floors = {}, {}
    for name, key in (("Combined", "combined"), ("Diffuse Direct", "diffuse_direct"),
                      ("Diffuse Indirect", "diffuse_indirect")):
        errors[key] = metrics.rel_l1(ours[name], ref.passes[name], mask)
        floors[key] = ref.noise_floor(name, mask)
    col_diff = np.abs(ours["Diffuse Color"] - ref.passes["Diffuse Color"]).max(axis=-1)
    report = {
        "method": method,
        "resolution": list(scene.resolution),
        "rel_l1": errors,
        "noise_floor": floors,
        "rel_mse": metrics.rel_mse(ours["Combined"], ref.passes["Combined"], mask),
        "diffuse_color_match": float(np.mean(col_diff[mask] < 0.01)) if mask.any() else float("nan"),
        "seconds": {"ours": result.timings["total"], "cycles": ref.seconds, "cycles_cached": ref.cached},
        "passes": {k: v for k, v in result.timings.items() if k != "total"},
        "reference": {"samples": samples, "seeds": 2, "bounces": bounces},
        "warnings": result.warnings + (["the world lights the scene in Cycles (Diffuse Direct), but method 'none' "
                                        "does not render world light"] if max(scene.world.color) > 0 and
                                       method == "none" else []),
        "pixels_compared": int(mask.sum()),
        "info": result.info,
    }
    return report, result, ref, mask


def cmd_compare(args) -> dict:
    heatmap = check_output_path(args.heatmap, ".png") if args.heatmap else None
    scene = load_scene(args.scene, tuple(args.res) if args.res else None)
    report, result, ref, mask = compare(scene, args.method, args.samples, args.bounces,
                                        lpv_options=parse_method_options(args.lpv),
                                        vct_settings=vct_options(args.vct))
    if heatmap:
        from ..gpu_kernels.output import exr as exr_io
        from ..gpu_kernels.output import metrics

        err = metrics.relative_error_map(result.passes["Combined"], ref.passes["Combined"]) * mask
        write_output(exr_io.write_png, heatmap, metrics.heatmap_rgb8(err))
        report["heatmap"] = heatmap
    if not args.json:
        print(format_compare(report))
    return report


def format_compare(report: dict) -> str:
    lines = [f"method {report['method']} at {report['resolution'][0]}x{report['resolution'][1]} vs Cycles "
             f"({report['reference']['samples']} spp x 2 seeds, {report['reference']['bounces']} bounces)",
             f"{'pass':<18}{'rel-L1':>10}{'noise floor':>14}"]
    for key, value in report["rel_l1"].items():
        lines.append(f"{key:<18}{value:>10.4f}{report['noise_floor'][key]:>14.4f}")
    lines.append(f"relMSE (Combined) {report['rel_mse']:.5f}; Diffuse Color match {report['diffuse_color_match']:.2%}")
    s = report["seconds"]
    lines.append(f"time: ours {s['ours'] * 1000:.1f} ms; Cycles {s['cycles']:.2f} s"
                 + (" (cached)" if s["cycles_cached"] else ""))
    lines += [f"warning: {w}" for w in report["warnings"]]
    return "\n".join(lines)


def cmd_bench(args) -> dict:
    """Time and error of our settings vs Cycles (± OIDN) and EEVEE; or --incremental / --scaling."""
    from .bench import check_out_dir, format_bench, run_bench

    if args.scaling:
        from .bench_scaling import format_scaling, run_scaling

        report = {"scaling": run_scaling(args.quick, _progress)}
        if not args.json:
            print(format_scaling(report["scaling"]))
        return report
    if not args.scenes:
        raise CliError("bench needs at least one .blend (or --scaling)")
    if args.incremental:
        from .bench_incremental import format_incremental, run_incremental

        paths = [check_blend_path(p) for p in args.scenes]
        report = {"incremental": [run_incremental(p, args.res, ("none", "lpv", "vct"), _progress,
                                                  1 if args.quick else 3) for p in paths]}
        if args.out:
            text = "".join(format_incremental(e) for e in report["incremental"])
            write_output(lambda path, t: open(path, "w").write(t),
                         os.path.join(check_out_dir(args.out), "incremental.md"), text)
        if not args.json:
            print("".join(format_incremental(e) for e in report["incremental"]))
        return report
    report = run_bench(args.scenes, args.quick, args.res, args.out, _progress, eevee=not args.no_eevee)
    if not args.json:
        print(format_bench(report))
    return report


class _ArgumentParser(argparse.ArgumentParser):
    """argparse, but a usage error is one line on stderr and exit code 2 like every other bad input."""

    def error(self, message):
        self.exit(EXIT_BAD_INPUT, f"bounce-gi: error: {message} (see bounce-gi --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from ..gpu_kernels.settings import METHODS

    parser = _ArgumentParser(prog="bounce-gi", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a .blend from its scene camera into a multi-layer EXR")
    r.add_argument("scene")
    r.add_argument("--method", choices=METHODS, help="default: none (with --budget-ms/--target-error: chosen)")
    r.add_argument("--res", nargs=2, type=int, metavar=("W", "H"))
    r.add_argument("--out", help="output .exr (default: next to the .blend)")
    r.add_argument("--budget-ms", type=float, metavar="MS",
                   help="choose method and settings: the most accurate measured to fit this frame time")
    r.add_argument("--target-error", type=float, metavar="E",
                   help="choose method and settings: the fastest measured to reach this Combined rel-L1")
    r.add_argument("--json", action="store_true", help="print one JSON object as the last stdout line")
    r.add_argument("--lpv", nargs="+", metavar="KEY=VALUE", help="LPV settings, e.g. bounces=4 resolution=32")
    r.add_argument("--vct", nargs="+", metavar="KEY=VALUE", help="VCT settings, e.g. bounces=4 resolution=64")
    r.set_defaults(func=cmd_render)
    c = sub.add_parser("compare", help="render and compare with a two-seed Cycles reference (cached)")
    c.add_argument("scene")
    c.add_argument("--method", choices=METHODS, default="none")
    c.add_argument("--samples", type=int, default=256)
    c.add_argument("--bounces", type=int, default=8, help="Cycles bounce count of the reference")
    c.add_argument("--res", nargs=2, type=int, metavar=("W", "H"))
    c.add_argument("--json", action="store_true")
    c.add_argument("--heatmap", help="write a per-pixel relative error heat map (PNG)")
    c.add_argument("--lpv", nargs="+", metavar="KEY=VALUE", help="LPV settings, e.g. bounces=4 resolution=32")
    c.add_argument("--vct", nargs="+", metavar="KEY=VALUE", help="VCT settings, e.g. bounces=4 resolution=64")
    c.set_defaults(func=cmd_compare)
    b = sub.add_parser("bench", help="time vs error of our settings, Cycles (± OIDN) and EEVEE; plots, summary.md")
    b.add_argument("scenes", nargs="*", metavar="SCENE")
    b.add_argument("--quick", action="store_true", help="few settings, 96x72, 64-spp reference, one timed run")
    b.add_argument("--res", nargs=2, type=int, metavar=("W", "H"))
    b.add_argument("--out", help="directory for plots, summary.md, quality_front.json (default: ./bounce-gi-bench)")
    b.add_argument("--json", action="store_true")
    b.add_argument("--incremental", action="store_true", help="time updates by kind of edit in one engine")
    b.add_argument("--scaling", action="store_true", help="time against triangles, grid size and resolution")
    b.add_argument("--no-eevee", action="store_true", help="skip the EEVEE peer (minutes on a software GL)")
    b.set_defaults(func=cmd_bench)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (exit 0) or a usage error already printed as one line (exit 2)
        return int(exc.code) if exc.code else 0
    try:
        if args.res and (args.res[0] < 1 or args.res[1] < 1):
            raise CliError("--res needs two positive integers")
        if getattr(args, "samples", 1) < 1:
            raise CliError("--samples must be at least 1")
        report = args.func(args)
    except CliError as exc:
        print(f"bounce-gi: error: {exc}", file=sys.stderr, flush=True)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("bounce-gi: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # never a traceback for the user; BOUNCE_GI_DEBUG=1 shows it
        if os.environ.get("BOUNCE_GI_DEBUG"):
            raise
        print(f"bounce-gi: internal error: {type(exc).__name__}: {exc} (set BOUNCE_GI_DEBUG=1 for details)",
              file=sys.stderr, flush=True)
        return EXIT_INTERNAL
    if args.json:
        sys.stdout.flush()
        print(json.dumps(report, default=float), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
