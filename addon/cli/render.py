# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi render`: one .blend rendered from its scene camera into a multi-layer EXR, with per-pass timings; with
`--frames A-B` an animation, one EXR a frame (frames.py)."""
from __future__ import annotations

import os

from ..scene_io import check_blend_path, check_output_path, load_scene, write_output
from .frames import render_frames
from .options import auto_quality, parse_method_options, render_ours, vct_options


def cmd_render(args) -> dict:
    quality = auto_quality(args)
    args.method = args.method or "none"
    if quality and not args.json:
        print(quality["message"])
    if args.frames is not None:
        return render_frames(args, quality)
    if args.out:
        out = check_output_path(args.out, ".exr")
    else:
        check_blend_path(args.scene)
        out = check_output_path(os.path.splitext(os.path.abspath(args.scene))[0] + f"_bounce_{args.method}.exr", ".exr")
    scene = load_scene(args.scene, tuple(args.res) if args.res else None)
    result = render_ours(scene, args.method, parse_method_options(args.lpv), vct_options(args.vct))
    from ...gpu_kernels.output import exr as exr_io

    write_output(exr_io.write_passes, out, result.passes)
    report = {"method": result.method, "resolution": list(result.resolution),
              "seconds": {k: round(v, 6) for k, v in result.timings.items()}, "skipped": result.skipped,
              "info": result.info, "skipped_work": result.info.get("skipped_work", []),
              "scene": result.statistics, "warnings": result.warnings, "output": out}
    if quality:
        report["quality"] = quality
    if not args.json:
        print(format_timings(result.timings))
        for w in result.warnings:
            print(f"warning: {w}")
        for text in report["skipped_work"]:
            print(f"skipped {text}")
        print(f"wrote {out}")
    return report


def format_timings(timings: dict) -> str:
    lines = [f"{'pass':<16}{'ms':>10}"]
    for name, seconds in timings.items():
        if name != "total":
            lines.append(f"{name:<16}{seconds * 1000:>10.2f}")
    lines.append(f"{'total':<16}{timings.get('total', 0) * 1000:>10.2f}")
    return "\n".join(lines)
