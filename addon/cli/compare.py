# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi compare`: render with Bounce GI and against a (cached) two-seed Cycles reference; the errors per pass
beside the reference's own noise floor, and optionally a heat map of the relative error."""
from __future__ import annotations

from ..scene_io import check_output_path, load_scene, progress, write_output
from .options import parse_method_options, render_ours, vct_options


def compare(scene, method: str, samples: int, bounces: int = 8, progress=progress, lpv_options=None,
            vct_settings=None) -> dict:
    """Render ours and the (cached) two-seed Cycles reference of the currently open scene; return the errors."""
    import numpy as np

    from ...gpu_kernels.output import metrics
    from ..reference.cycles import ReferenceSettings, render_reference

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
        from ...gpu_kernels.output import exr as exr_io
        from ...gpu_kernels.output import metrics

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
