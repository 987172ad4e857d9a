# SPDX-License-Identifier: GPL-3.0-or-later
"""Time Bounce GI's direct-light render of example scenes: cold (first render: shader compile included), warm full
(every pass re-run, programs compiled) and unchanged (all passes skipped). Prints a table; asserts nothing.

    .venv/bin/python benchmarks/time_direct.py [--res 640 480] [--repeats 5] [scene ...]
"""
import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scenes", nargs="*", default=["cornell", "light_mixed", "cornell_emissive"])
    parser.add_argument("--res", nargs=2, type=int, default=(640, 480))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    import bpy

    from bounce_gi.addon.extract import extract_scene
    from bounce_gi.gpu_kernels.engine import Engine
    from bounce_gi.gpu_kernels.settings import RenderSettings
    from examples import scenes

    engine = Engine()
    info = engine.gl_info()
    print(f"GL: {info['renderer']} ({info['version']}); resolution {args.res[0]}x{args.res[1]}")
    settings = RenderSettings("none", *args.res)
    for name in args.scenes:
        scenes.build(name)
        scene = extract_scene(bpy.context.evaluated_depsgraph_get(), tuple(args.res))
        start = time.perf_counter()
        engine.render(scene, settings)
        cold = time.perf_counter() - start
        full, per_pass = [], []
        for _ in range(args.repeats):
            engine.clear_cache()
            start = time.perf_counter()
            result = engine.render(scene, settings)
            full.append(time.perf_counter() - start)
            per_pass.append(result.timings)
        start = time.perf_counter()
        engine.render(scene, settings)
        unchanged = time.perf_counter() - start
        med = statistics.median(full)
        passes = {k: statistics.median(t[k] for t in per_pass) for k in per_pass[0] if k != "total"}
        print(f"\n{name}: {scene.triangle_count} triangles, {len(scene.lights)} lights")
        print(f"  cold {cold * 1000:.0f} ms; warm full median {med * 1000:.0f} ms (of {args.repeats}); "
              f"unchanged {unchanged * 1000:.1f} ms")
        print("  " + ", ".join(f"{k} {v * 1000:.1f}" for k, v in passes.items()) + " (ms, median)")


if __name__ == "__main__":
    main()
