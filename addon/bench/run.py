"""`bounce-gi bench`: time and error of our methods against a two-seed Cycles reference, beside Cycles (± OIDN)
and EEVEE peers rendered in the same run at the same resolution (bench_peers.py); Pareto front, speed-ups at equal
error, log-log plot and summary.md (bench_report.py); the table automatic quality picks from (quality.py).

Rows (ours): a warm-up render (shader compilation, uploads), then the median of N full frames, each with every pass
cache cleared, plus the scene extraction time (an update in Blender extracts too, and the Cycles peers' times
include their scene sync). Errors over pixels that hit geometry (design.md §3): rel-L1 of Combined and Diffuse
Indirect, relMSE of Combined, FLIP of Combined (tone-mapped sRGB; in a subprocess because flip-evaluator calls
sys.exit on bad input). A row that fails records "error" instead of ending the run.
"""
from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import asdict, replace

from .bench_report import pareto, row_label, speedups, summary_markdown, write_plot

QUICK_RES = (96, 72)
QUALITY_FILE = "quality_front.json"  # what the bench writes for automatic quality (quality.py reads it)
# The settings a sweep varies per method; the summary names rows by these.
SWEPT_KEYS = {"lpv": ("transport", "resolution", "cascades", "gather_vpls", "max_iterations", "bounces"),
              "vct": ("resolution", "diffuse_cones", "bounces", "gathered_bounces", "indirect_scale")}
FLIP_CODE = ("import sys, flip_evaluator as f; "
             "print('FLIP', float(f.evaluate(sys.argv[1], sys.argv[2], 'LDR', applyMagma=False)[1]))")


def default_settings(method: str) -> dict:
    from ..gpu_kernels.lpv.settings import LpvSettings
    from ..gpu_kernels.vct.settings import VctSettings

    cls = {"lpv": LpvSettings, "vct": VctSettings}.get(method)
    return asdict(cls()) if cls else {}


def _finite(x):
    return float(x) if x is not None and math.isfinite(float(x)) else None


def sweep(quick: bool, width: int, height: int) -> list:
    """(method, settings dict, RenderSettings, default) for every row; default = the settings `render` uses."""
    from ..gpu_kernels.lpv.settings import LpvSettings
    from ..gpu_kernels.settings import RenderSettings
    from ..gpu_kernels.vct.settings import VctSettings

    base = RenderSettings(width=width, height=height)
    rows = [("none", {}, replace(base, method="none"), True)]
    # LPV: the gathered transport (default) from its cheap corner (16³, 1 bounce) to twice the VPLs and three
    # cascades; the propagating transport at the 3 bounces it was measured with, and with 16 iterations.
    lpv = [dict(resolution=16, bounces=1), {}] if quick else [
        dict(resolution=16, bounces=1), dict(resolution=16), dict(resolution=32, bounces=1), {},
        dict(gather_vpls=1024), dict(cascades=3), dict(transport="propagate", bounces=3),
        dict(transport="propagate", bounces=3, max_iterations=16)]
    # VCT: the cheap corner (32³, 6 cones, 1 bounce), a fast multi-bounce point, the single bounce at 64³, the
    # default, every bounce gathered (what the extrapolated tail saves), 128³, and reduced-resolution tracing.
    vct = [dict(resolution=32, diffuse_cones=6, bounces=1), {}] if quick else [
        dict(resolution=32, diffuse_cones=6, bounces=1), dict(resolution=32, diffuse_cones=6, gathered_bounces=3),
        dict(diffuse_cones=6, bounces=1), {}, dict(gathered_bounces=0), dict(resolution=128, bounces=1),
        dict(indirect_scale=2), dict(indirect_scale=4)]
    for changes in lpv:
        s = replace(LpvSettings(), **changes)
        rows.append(("lpv", asdict(s), replace(base, method="lpv", lpv=s), s == LpvSettings()))
    for changes in vct:
        s = replace(VctSettings(), **changes)
        rows.append(("vct", asdict(s), replace(base, method="vct", vct=s), s == VctSettings()))
    return rows


def geometry_mask(ours: dict, ref: dict):
    return (ours["Position"].any(axis=-1) | (ours["Depth"][..., 0] < 1e9)) & (ref["Depth"][..., 0] < 1e9)


def flip_error(test_rgb, ref_rgb, tmp: str):
    """Mean FLIP of tone-mapped sRGB PNGs, computed in a subprocess; (value or None, warning or None)."""
    from ..gpu_kernels.output import exr as exr_io

    ref_png, test_png = os.path.join(tmp, "flip_ref.png"), os.path.join(tmp, "flip_test.png")
    try:
        exr_io.write_png(ref_png, exr_io.tonemap_srgb(ref_rgb))
        exr_io.write_png(test_png, exr_io.tonemap_srgb(test_rgb))
        proc = subprocess.run([sys.executable, "-c", FLIP_CODE, ref_png, test_png], capture_output=True, text=True,
                              timeout=300)
        for line in proc.stdout.splitlines():
            if line.startswith("FLIP "):
                return _finite(float(line.split()[1])), None
        tail = (proc.stderr.strip().splitlines() or [f"exit code {proc.returncode}"])[-1]
        return None, f"FLIP failed: {tail}"
    except (OSError, subprocess.SubprocessError, ValueError) as exc:
        return None, f"FLIP failed: {exc}"


def time_extraction(resolution, repeats: int) -> float:
    """Median seconds to extract the open bpy scene (what every update in Blender pays before rendering)."""
    import bpy

    from .extract import extract_scene

    runs = []
    for _ in range(max(1, repeats)):
        start = time.perf_counter()
        extract_scene(bpy.context.evaluated_depsgraph_get(), resolution)
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


def time_ours(engine, scene, settings, repeats: int):
    """Warm-up, then `repeats` full renders with the pass cache cleared; (median seconds, median per pass, last)."""
    engine.render(scene, settings)  # compiles shaders, uploads
    runs = []
    for _ in range(repeats):
        engine.clear_cache()
        start = time.perf_counter()
        result = engine.render(scene, settings)
        runs.append((time.perf_counter() - start, result))
    seconds = statistics.median(r[0] for r in runs)
    names = [k for k in runs[-1][1].timings if k != "total"]
    passes = {k: statistics.median(r[1].timings.get(k, 0.0) for r in runs) for k in names}
    return seconds, passes, runs[-1][1]


def bench_row(engine, scene, ref, row, repeats, extract_seconds, tmp, progress) -> dict:
    from ..gpu_kernels.output import metrics

    method, settings_dict, settings, default = row
    out = {"method": method, "settings": settings_dict, "default": default, "seconds": None, "passes": {},
           "rel_l1": {"combined": None, "diffuse_indirect": None}, "rel_mse": None, "flip": None, "warnings": []}
    progress(f"bench: {row_label(out)}")
    try:
        seconds, passes, result = time_ours(engine, scene, settings, repeats)
    except Exception as exc:  # noqa: BLE001 — one failing setting must not end the benchmark
        out["error"] = f"{type(exc).__name__}: {exc}"
        progress(f"bench: {row_label(out)} failed: {out['error']}")
        if os.environ.get("BOUNCE_GI_DEBUG"):
            traceback.print_exc()
        return out
    ours = result.passes
    mask = geometry_mask(ours, ref.passes)
    out.update(seconds=extract_seconds + seconds, passes={"extract": extract_seconds, **passes},
               warnings=list(result.warnings), info=result.info)
    out["rel_l1"] = {"combined": _finite(metrics.rel_l1(ours["Combined"], ref.passes["Combined"], mask)),
                     "diffuse_indirect": _finite(metrics.rel_l1(ours["Diffuse Indirect"],
                                                                ref.passes["Diffuse Indirect"], mask))}
    out["rel_mse"] = _finite(metrics.rel_mse(ours["Combined"], ref.passes["Combined"], mask))
    out["flip"], warning = flip_error(ours["Combined"], ref.passes["Combined"], tmp)
    if warning:
        out["warnings"].append(warning)
    return out


def bench_scene(path, quick, res, tmp, progress, eevee=True) -> dict:
    from ..gpu_kernels.engine import get_engine
    from .bench_peers import render_peers
    from .cli import load_scene
    from .reference.cycles import ReferenceSettings, render_reference

    resolution = tuple(res) if res else (QUICK_RES if quick else None)
    scene = load_scene(path, resolution)
    width, height = scene.resolution
    ref_settings = ReferenceSettings(width, height, samples=64 if quick else 256)
    progress(f"bench: {os.path.basename(path)} at {width}x{height}")
    ref = render_reference(scene.content_hash(), ref_settings, progress=progress)
    ref_mask = ref.passes["Depth"][..., 0] < 1e9
    engine = get_engine()
    repeats = 1 if quick else 3
    extract_seconds = time_extraction(resolution, repeats)
    rows = [bench_row(engine, scene, ref, row, repeats, extract_seconds, tmp, progress)
            for row in sweep(quick, width, height)]
    peers, warnings = render_peers(ref, ref_mask, width, height, quick, progress, tmp, eevee)
    entry = {"scene": os.path.abspath(path), "name": os.path.splitext(os.path.basename(path))[0],
             "resolution": [width, height],
             "reference": {"samples": ref_settings.samples, "seeds": len(ref_settings.seeds),
                           "bounces": ref_settings.bounces, "seconds": ref.seconds, "cached": ref.cached,
                           "noise_floor": {"combined": _finite(ref.noise_floor("Combined", ref_mask)),
                                           "diffuse_indirect": _finite(ref.noise_floor("Diffuse Indirect",
                                                                                       ref_mask))}},
             "rows": rows, "peers": peers, "pareto": pareto(rows, peers), "warnings": warnings}
    entry["speedups"] = speedups(entry)
    return entry


def check_out_dir(path: str) -> str:
    from .cli import CliError

    path = os.path.abspath(path)
    if os.path.exists(path) and not os.path.isdir(path):
        raise CliError(f"--out {path}: exists and is not a directory")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise CliError(f"--out {path}: cannot create it ({exc.strerror})") from None
    if not os.access(path, os.W_OK):
        raise CliError(f"--out {path}: not writable")
    return path


def quality_table(report: dict) -> dict:
    """Our settings over all benched scenes: median seconds and mean Combined rel-L1 per setting, and which lie on
    the Pareto front of those aggregates. Automatic quality (quality.py) chooses from this."""
    by_label = {}
    for s in report["scenes"]:
        for r in s["rows"]:
            if r["seconds"] is not None and r["rel_l1"]["combined"] is not None:
                by_label.setdefault(row_label(r), []).append(r)
    entries = []
    for label, rows in by_label.items():
        if len(rows) != len(report["scenes"]):
            continue  # failed on some scene: not a setting to recommend
        entries.append({"label": label, "method": rows[0]["method"], "settings": rows[0]["settings"],
                        "seconds": statistics.median(r["seconds"] for r in rows),
                        "rel_l1": statistics.fmean(r["rel_l1"]["combined"] for r in rows)})
    front = {p["label"] for p in pareto([{"method": e["method"], "settings": e["settings"], "seconds": e["seconds"],
                                          "rel_l1": {"combined": e["rel_l1"]}} for e in entries], [])}
    for e in entries:
        e["pareto"] = e["label"] in front
    return {"machine": report.get("machine", {}), "scenes": [s["name"] for s in report["scenes"]],
            "resolutions": [s["resolution"] for s in report["scenes"]], "quick": report["quick"],
            "entries": sorted(entries, key=lambda e: e["seconds"])}


def _write_text(path: str, text: str) -> None:
    """Write through a temporary file, so an interrupted run never leaves a half-written file."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def run_bench(scenes: list, quick: bool, res, out_dir: str | None, progress, eevee: bool = True) -> dict:
    """The whole benchmark: every scene, plots, summary.md and quality_front.json in out_dir; returns the report."""
    from ..gpu_kernels.engine import get_engine
    from .cli import check_blend_path

    paths = [check_blend_path(p) for p in scenes]  # all bad input is reported before anything renders
    out_dir = check_out_dir(out_dir or "bounce-gi-bench")
    report = {"quick": quick, "out": out_dir, "machine": machine_info(get_engine()), "scenes": [], "plots": []}
    with tempfile.TemporaryDirectory(prefix="bounce-gi-bench-") as tmp:
        for path in paths:
            entry = bench_scene(path, quick, res, tmp, progress, eevee)
            report["scenes"].append(entry)
            plot = os.path.join(out_dir, f"{entry['name']}_time_vs_error.png")
            try:
                write_plot(plot, entry)
                report["plots"].append(plot)
            except Exception as exc:  # noqa: BLE001 — a plot is a convenience, the numbers are the result
                entry["warnings"].append(f"plot failed: {exc}")
    report["summary"] = os.path.join(out_dir, "summary.md")
    _write_text(report["summary"], summary_markdown(report))
    report["quality_table"] = os.path.join(out_dir, QUALITY_FILE)
    _write_text(report["quality_table"], json.dumps(quality_table(report), indent=1))
    _write_text(os.path.join(out_dir, "bench.json"), json.dumps(report, indent=1, default=float))
    return report


def machine_info(engine) -> dict:
    import platform

    info = {"cpu_count": os.cpu_count(), "platform": platform.platform()}
    try:
        gl = engine.gl_info()
        info["gl_renderer"] = gl["renderer"]
        info["gl_version"] = gl["version"]
    except Exception as exc:  # noqa: BLE001 — the report says so rather than failing
        info["gl_renderer"] = f"unknown ({exc})"
    return info


def format_bench(report: dict) -> str:
    """Plain-text output: the summary table and where the files went."""
    return summary_markdown(report) + f"\nwrote {report['summary']}, {report['quality_table']}"
