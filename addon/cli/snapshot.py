# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi snapshot`: what the viewport draws, from the scene camera, into an EXR (a Combined layer,
scene-linear) or a PNG (Standard view transform) — the viewport's drawing path (ui/draw.py) run headless."""
from __future__ import annotations

from ..scene_io import CliError, check_output_path, load_scene, write_output
from .options import engine_result, method_settings

SUFFIXES = (".exr", ".png")


def cmd_snapshot(args) -> dict:
    suffix = next((s for s in SUFFIXES if args.out.lower().endswith(s)), None)
    if suffix is None:
        raise CliError(f"{args.out}: output must be an .exr or .png file")
    out = check_output_path(args.out, suffix)
    scene = load_scene(args.scene, tuple(args.res) if args.res else None)
    settings = method_settings(scene, args.method or "none", args.lpv, args.vct)
    from ...gpu_kernels.engine import get_engine
    from ...ui import draw

    light = engine_result(lambda: get_engine().submit_surface(scene, settings, args.texels).result())
    width, height = (int(v) for v in scene.resolution)
    image = draw.snapshot(light, scene, width, height, args.display.upper())
    if suffix == ".exr":
        from ...gpu_kernels.output.exr import write_passes

        write_output(write_passes, out, {"Combined": image})
    else:
        from ...gpu_kernels.output.png import write_png

        write_output(write_png, out, image)
    report = {"method": light.method, "resolution": [width, height], "texels": light.atlas.texel_count,
              "texel_size": light.atlas.texel, "seconds": {k: round(v, 6) for k, v in light.timings.items()},
              "warnings": light.warnings, "output": out}
    if not args.json:
        for w in light.warnings:
            print(f"warning: {w}")
        print(f"wrote {out}")
    return report
