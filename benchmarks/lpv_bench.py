"""LPV time per pass and error against Cycles for example scenes, over grid size, cascades and bounces.
Prints a table (median of --repeats full re-renders after a warm-up); asserts nothing.

    .venv/bin/python benchmarks/lpv_bench.py [--scenes cornell spot_room courtyard] [--res 160 120] [--samples 64]
"""
import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

CONFIGS = [dict(resolution=32, cascades=1), dict(resolution=32, cascades=3), dict(resolution=64, cascades=1),
           dict(resolution=64, cascades=3)]
PASSES = ("rsm", "lpv_inject", "geometry_volume", "lpv_propagate", "lpv_lighting")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scenes", nargs="+", default=["cornell", "spot_room", "courtyard"])
    parser.add_argument("--res", nargs=2, type=int, default=(160, 120))
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples per seed (0: skip the errors)")
    parser.add_argument("--bounces", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()

    import bpy

    from bounce_gi.addon.cycles_reference import ReferenceSettings, render_reference
    from bounce_gi.addon.extract import extract_scene
    from bounce_gi.gpu_kernels import metrics
    from bounce_gi.gpu_kernels.engine import Engine
    from bounce_gi.gpu_kernels.lpv import LpvSettings
    from bounce_gi.gpu_kernels.pipeline import RenderSettings
    from examples import scenes

    engine = Engine()
    print(f"GL: {engine.gl_info()['renderer']}; image {args.res[0]}x{args.res[1]}; bounces {args.bounces}")
    header = f"{'scene':<11}{'grid':>6}{'casc':>5}{'iters':>7}" + "".join(f"{p:>16}" for p in PASSES) + \
        f"{'total ms':>10}{'DI relL1':>10}{'Comb relL1':>11}"
    print(header)
    for name in args.scenes:
        scenes.build(name)
        scene = extract_scene(bpy.context.evaluated_depsgraph_get(), tuple(args.res))
        ref = None
        if args.samples:
            ref = render_reference(scene.content_hash(), ReferenceSettings(*args.res, samples=args.samples))
        for cfg in CONFIGS:
            settings = RenderSettings("lpv", *args.res, lpv=LpvSettings(bounces=args.bounces, **cfg))
            engine.render(scene, settings)  # warm-up: compiles shaders
            runs = []
            for _ in range(args.repeats):
                engine.worker.call(lambda ctx: engine._pipeline.cache.clear())
                start = time.perf_counter()
                result = engine.render(scene, settings)
                runs.append((time.perf_counter() - start, result))
            total = statistics.median(r[0] for r in runs)
            result = runs[-1][1]
            times = [statistics.median(r[1].timings.get(p, 0.0) for r in runs) * 1000 for p in PASSES]
            iters = sum(c["iterations"] for c in result.info["cascades"])
            errors = ""
            if ref is not None:
                mask = (ref.passes["Depth"][..., 0] < 1e9) & (result.passes["Depth"][..., 0] < 1e9)
                errors = (f"{metrics.rel_l1(result.passes['Diffuse Indirect'], ref.passes['Diffuse Indirect'], mask):>10.3f}"
                          f"{metrics.rel_l1(result.passes['Combined'], ref.passes['Combined'], mask):>11.3f}")
            print(f"{name:<11}{cfg['resolution']:>5}³{cfg['cascades']:>5}{iters:>7}" +
                  "".join(f"{t:>16.1f}" for t in times) + f"{total * 1000:>10.0f}" + errors, flush=True)


if __name__ == "__main__":
    main()
