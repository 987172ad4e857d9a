# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi compare`: render with Bounce GI and against a (cached) two-seed Cycles reference; the errors per pass
beside the reference's own noise floor, and optionally a heat map of the relative error."""
from __future__ import annotations

import math

from ..scene_io import check_output_path, load_scene, progress, write_output
from .options import parse_method_options, render_ours, vct_options


def compare(scene, method: str, samples: int, bounces: int = 8, progress=progress, lpv_options=None,
            vct_settings=None) -> tuple:
    """Render ours and the (cached) two-seed Cycles reference of the currently open scene; return
    (report, result, reference, mask) (addon/reference/compare.py)."""
    from ..reference.compare import compare_result
    from ..reference.cycles import ReferenceSettings, render_reference

    result = render_ours(scene, method, lpv_options, vct_settings)
    ref_settings = ReferenceSettings(scene.resolution[0], scene.resolution[1], samples=samples, bounces=bounces)
    ref = render_reference(scene.content_hash(), ref_settings, progress=progress)
    report, mask = compare_result(scene, result, ref, method, samples, bounces)
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
        from ..reference.compare import error_map

        write_output(exr_io.write_png, heatmap, metrics.heatmap_rgb8(error_map(result, ref, mask)))
        report["heatmap"] = heatmap
    if not args.json:
        print(format_compare(report))
    return report


def format_compare(report: dict) -> str:
    lines = [f"method {report['method']} at {report['resolution'][0]}x{report['resolution'][1]} vs Cycles "
             f"({report['reference']['samples']} spp x 2 seeds, {report['reference']['bounces']} bounces)",
             f"{'pass':<18}{'rel-L1':>10}{'noise floor':>14}"]
    for key, value in report["rel_l1"].items():
        if math.isnan(value):  # rel-L1 divides by Cycles' pass, which is black over every compared pixel
            lines.append(f"{key:<18}{'—':>10}{'—':>14}   (Cycles' pass is 0 where both hit geometry)")
        else:
            lines.append(f"{key:<18}{value:>10.4f}{report['noise_floor'][key]:>14.4f}")
    lines.append(f"relMSE (Combined) {report['rel_mse']:.5f}; Diffuse Color match {report['diffuse_color_match']:.2%}")
    s = report["seconds"]
    lines.append(f"time: ours {s['ours'] * 1000:.1f} ms; Cycles {s['cycles']:.2f} s"
                 + (" (cached)" if s["cycles_cached"] else ""))
    lines += [f"warning: {w}" for w in report["warnings"]]
    return "\n".join(lines)
