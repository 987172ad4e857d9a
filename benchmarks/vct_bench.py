"""VCT time per pass and error against Cycles for example scenes, over grid size and image size.
Prints a table (median of --repeats full re-renders after a warm-up render that compiles the shaders); asserts
nothing. Errors are rel-L1 over pixels that hit geometry, against the mean of two Cycles seeds (64 spp, 8 bounces
by default), with the reference's own noise floor (half the rel-L1 between its seeds) beside them.

    .venv/bin/python benchmarks/vct_bench.py [--scenes cornell spot_room courtyard] [--grids 64 128]
        [--res 320x240 640x480] [--bounces 1] [--samples 64] [--repeats 2]
"""
import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

PASSES = ("vct_voxelize", "vct_inject", "vct_mipmap", "vct_bounce", "vct_trace")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scenes", nargs="+", default=["cornell", "spot_room", "courtyard"])
    parser.add_argument("--grids", nargs="+", type=int, default=[64, 128])
    parser.add_argument("--res", nargs="+", default=["320x240", "640x480"])
    parser.add_argument("--bounces", type=int, default=1, help="VCT bounces (VctSettings.bounces)")
    parser.add_argument("--anisotropic", type=int, default=1, help="1: anisotropic volumes (default), 0: isotropic")
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples per seed (0: skip the errors)")
    parser.add_argument("--ref-bounces", type=int, default=8, help="Cycles bounces")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()

    import bpy

    from bounce_gi.addon.cycles_reference import ReferenceSettings, render_reference
    from bounce_gi.addon.extract import extract_scene
    from bounce_gi.gpu_kernels import metrics
    from bounce_gi.gpu_kernels.engine import Engine
    from bounce_gi.gpu_kernels.pipeline import RenderSettings
    from bounce_gi.gpu_kernels.vct import VctSettings
    from examples import scenes

    engine = Engine()
    print(f"GL: {engine.gl_info()['renderer']}; VCT bounces {args.bounces}, "
          f"{'anisotropic' if args.anisotropic else 'isotropic'}; Cycles {args.samples} spp x 2 seeds, "
          f"{args.ref_bounces} bounces; times: median of {args.repeats} after a warm-up (ms)")
    header = (f"{'scene':<11}{'grid':>6}{'image':>9}" + "".join(f"{p[4:]:>10}" for p in PASSES) +
              f"{'total':>9}{'DI relL1':>10}{'(floor)':>8}{'Comb relL1':>11}{'(floor)':>8}")
    print(header)
    for name in args.scenes:
        for res in args.res:
            w, h = (int(v) for v in res.lower().split("x"))
            scenes.build(name)
            scene = extract_scene(bpy.context.evaluated_depsgraph_get(), (w, h))
            ref = None
            if args.samples:
                ref = render_reference(scene.content_hash(), ReferenceSettings(w, h, samples=args.samples,
                                                                               bounces=args.ref_bounces))
            for grid in args.grids:
                vs = VctSettings(resolution=grid, bounces=args.bounces, anisotropic=bool(args.anisotropic))
                settings = RenderSettings("vct", w, h, vct=vs)
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
                errors = ""
                if ref is not None:
                    mask = (ref.passes["Depth"][..., 0] < 1e9) & (result.passes["Depth"][..., 0] < 1e9)
                    errors = "".join(f"{metrics.rel_l1(result.passes[p], ref.passes[p], mask):>10.3f}"
                                     f"{ref.noise_floor(p, mask):>8.3f} " for p in ("Diffuse Indirect", "Combined"))
                print(f"{name:<11}{grid:>5}³{res:>9}" + "".join(f"{t:>10.0f}" for t in times) +
                      f"{total * 1000:>9.0f}" + errors, flush=True)


if __name__ == "__main__":
    main()
