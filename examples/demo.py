# SPDX-License-Identifier: GPL-3.0-or-later
"""`make demo`: build the Cornell box example, render it with Bounce GI, compare with Cycles, print a table.

Writes into --out (default out/demo): cornell.blend; per method, cornell_<method>.exr (Cycles-named passes), PNG
previews (combined, diffuse direct/indirect, diffuse colour) and an error heat map; Cycles' combined as a PNG.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bounce_gi.addon.cli import compare, format_compare, format_timings  # noqa: E402
from bounce_gi.gpu_kernels.output import exr as exr_io  # noqa: E402
from bounce_gi.gpu_kernels.output import metrics
from bounce_gi.gpu_kernels.gl.context import GpuUnavailableError  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/demo")
    parser.add_argument("--scene", default="cornell")
    parser.add_argument("--res", nargs=2, type=int, default=(320, 240))
    parser.add_argument("--samples", type=int, default=128, help="Cycles samples per seed for the reference")
    parser.add_argument("--methods", nargs="+", default=["none", "lpv", "vct"], choices=["none", "lpv", "vct"])
    args = parser.parse_args()

    import bpy

    from bounce_gi.addon.extract import extract_scene
    from examples import scenes

    os.makedirs(args.out, exist_ok=True)
    blend = os.path.join(args.out, f"{args.scene}.blend")
    scenes.save(args.scene, blend)
    scene = extract_scene(bpy.context.evaluated_depsgraph_get(), tuple(args.res))
    print(f"scene {args.scene}: {scene.triangle_count} triangles, {len(scene.lights)} lights, "
          f"{args.res[0]}x{args.res[1]}", flush=True)
    for method in args.methods:
        try:
            report, result, ref, mask = compare(scene, method, args.samples, progress=lambda m: print(m, flush=True))
        except GpuUnavailableError as exc:
            print(f"demo: {exc}", file=sys.stderr)
            return 2
        stem = os.path.join(args.out, f"{args.scene}_{method}")
        exr_io.write_passes(stem + ".exr", result.passes)
        previews = {"combined": result.passes["Combined"], "diffuse_direct": result.passes["Diffuse Direct"],
                    "diffuse_indirect": result.passes["Diffuse Indirect"],
                    "diffuse_color": result.passes["Diffuse Color"]}
        for name, image in previews.items():
            exr_io.write_png(f"{stem}_{name}.png", exr_io.tonemap_srgb(image))
        exr_io.write_png(os.path.join(args.out, f"{args.scene}_cycles_combined.png"),
                         exr_io.tonemap_srgb(ref.passes["Combined"]))
        err = metrics.relative_error_map(result.passes["Combined"], ref.passes["Combined"]) * mask
        exr_io.write_png(f"{stem}_error_heatmap.png", metrics.heatmap_rgb8(err))
        print(f"\n=== method {method} ===")
        print(format_timings(result.timings))
        print()
        print(format_compare(report))
        print(f"wrote {stem}.exr and PNG previews")
    if "none" in args.methods:
        print("\nMethod 'none' is direct light only: its Diffuse Indirect error is 1 by definition.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
