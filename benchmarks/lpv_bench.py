# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV time per pass and error against Cycles for example scenes, over grid size, cascades and bounces.
Prints a table (median of --repeats full re-renders after a warm-up); asserts nothing.

    .venv/bin/python benchmarks/lpv_bench.py [--scenes cornell spot_room courtyard] [--res 160 120] [--samples 64]
                                             [--transports gather propagate]

--octree: Olovsson and Doggett 2013's Table 1 instead — per-step ms (inject, downsample, propagate, merge, lighting) and iteration
counts of the octree LPV (k = 4 per level) against the uniform grid (k = 16 and the adaptive default), at 32³, with
the errors against Cycles, then the paper's e_abs / e_rel (§4.1) after each octree iteration.
"""
import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# Both transports (gpu_kernels/lpv/gather.py): the gather at its defaults (8 bounces, 4 gathered), the propagation
# at 3 bounces as it was measured before the gather existed.
CONFIGS = [dict(transport=t, resolution=n, cascades=c, **({} if t == "gather" else {"bounces": 3}))
           for t in ("gather", "propagate") for n in (32, 64) for c in (1, 3)]
PASSES = ("rsm", "lpv_inject", "geometry_volume", "lpv_propagate", "lpv_lighting")
OCTREE_CONFIGS = [("uniform k=16", dict(max_iterations=16, epsilon=0.0)), ("uniform adaptive", dict()),
                  ("uniform k=16 int 1b", dict(max_iterations=16, epsilon=0.0, lookup="intensity", bounces=1)),
                  ("octree L=3 k=4", dict(octree_levels=3, octree_iterations=4)),
                  ("octree L=4 k=4", dict(octree_levels=4, octree_iterations=4))]
OCTREE_PASSES = ("rsm", "geometry_volume", "lpv_octree_geometry", "lpv_inject", "lpv_downsample", "lpv_propagate",
                 "lpv_merge", "lpv_lighting")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scenes", nargs="+", default=["cornell", "spot_room", "courtyard"])
    parser.add_argument("--res", nargs=2, type=int, default=(160, 120))
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples per seed (0: skip the errors)")
    parser.add_argument("--bounces", type=int, default=None, help="override every configuration's bounce count")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--transports", nargs="+", default=["gather", "propagate"], choices=["gather", "propagate"])
    parser.add_argument("--octree", action="store_true", help="Olovsson and Doggett 2013, Table 1: octree vs uniform at 32³")
    args = parser.parse_args()

    import bpy

    from bounce_gi.addon.reference.cycles import ReferenceSettings, render_reference
    from bounce_gi.addon.extract import extract_scene
    from bounce_gi.gpu_kernels.output import metrics
    from bounce_gi.gpu_kernels.engine import Engine
    from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
    from bounce_gi.gpu_kernels.settings import RenderSettings
    from examples import scenes

    engine = Engine()
    print(f"GL: {engine.gl_info()['renderer']}; image {args.res[0]}x{args.res[1]}; bounces "
          f"{args.bounces or 'gather 8 (4 gathered), propagate 3'}")
    if args.octree:
        return octree_table(args, engine, scenes, extract_scene, render_reference, ReferenceSettings, metrics)
    header = f"{'scene':<11}{'transport':>10}{'grid':>6}{'casc':>5}{'iters':>7}{'VPLs':>7}" + \
        "".join(f"{p:>16}" for p in PASSES) + \
        f"{'total ms':>10}{'DI relL1':>10}{'Comb relL1':>11}"
    print(header)
    for name in args.scenes:
        scenes.build(name)
        scene = extract_scene(bpy.context.evaluated_depsgraph_get(), tuple(args.res))
        ref = None
        if args.samples:
            ref = render_reference(scene.content_hash(), ReferenceSettings(*args.res, samples=args.samples))
        for cfg in (c for c in CONFIGS if c["transport"] in args.transports):
            settings = RenderSettings("lpv", *args.res, lpv=LpvSettings(
                **{**cfg, **({"bounces": args.bounces} if args.bounces else {})}))
            runs = timed_runs(engine, scene, settings, args.repeats)
            total = statistics.median(r[0] for r in runs)
            result = runs[-1][1]
            times = [statistics.median(r[1].timings.get(p, 0.0) for r in runs) * 1000 for p in PASSES]
            iters = sum(c["iterations"] for c in result.info["cascades"])
            vpls = sum(b.get("vpls", 0) for c in result.info["cascades"] for b in c["bounces"])
            errors = ""
            if ref is not None:
                mask = (ref.passes["Depth"][..., 0] < 1e9) & (result.passes["Depth"][..., 0] < 1e9)
                errors = (f"{metrics.rel_l1(result.passes['Diffuse Indirect'], ref.passes['Diffuse Indirect'], mask):>10.3f}"
                          f"{metrics.rel_l1(result.passes['Combined'], ref.passes['Combined'], mask):>11.3f}")
            print(f"{name:<11}{cfg['transport']:>10}{cfg['resolution']:>5}³{cfg['cascades']:>5}{iters:>7}{vpls:>7}" +
                  "".join(f"{t:>16.1f}" for t in times) + f"{total * 1000:>10.0f}" + errors, flush=True)


def timed_runs(engine, scene, settings, repeats):
    """(seconds, result) of `repeats` full re-renders (pass cache cleared) after a warm-up that compiles shaders."""
    engine.render(scene, settings)  # warm-up: compiles shaders
    runs = []
    for _ in range(repeats):
        engine.clear_cache()
        start = time.perf_counter()
        result = engine.render(scene, settings)
        runs.append((time.perf_counter() - start, result))
    return runs


def octree_table(args, engine, scenes, extract_scene, render_reference, ReferenceSettings, metrics):
    import bpy

    from bounce_gi.gpu_kernels.lpv import octree as lpv_octree
    from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
    from bounce_gi.gpu_kernels.settings import RenderSettings

    cols = ("inject", "GV", "IX+GVdown", "downsample", "propagate", "merge", "lighting", "LPV total", "frame")
    for name in args.scenes:
        scenes.build(name)
        scene = extract_scene(bpy.context.evaluated_depsgraph_get(), tuple(args.res))
        ref = render_reference(scene.content_hash(), ReferenceSettings(*args.res, samples=args.samples)) \
            if args.samples else None
        print(f"\n{name}, 32³, {args.res[0]}x{args.res[1]}: ms per step (median of {args.repeats}); iterations; "
              "rel-L1 vs Cycles" + (f" (noise floor DI {ref.noise_floor('Diffuse Indirect'):.3f}, "
                                    f"Combined {ref.noise_floor('Combined'):.3f})" if ref else ""))
        print(f"{'config':<21}{'iters':>12}" + "".join(f"{c:>11}" for c in cols) + f"{'DI relL1':>10}{'Comb':>8}")
        for label, cfg in OCTREE_CONFIGS:
            settings = RenderSettings("lpv", *args.res, lpv=LpvSettings(
                resolution=32, transport="propagate", **{"bounces": args.bounces or 3, **cfg}))
            runs = timed_runs(engine, scene, settings, args.repeats)
            result = runs[-1][1]
            ms = {p: statistics.median(r[1].timings.get(p, 0.0) for r in runs) * 1000 for p in OCTREE_PASSES}
            lpv_ms = sum(ms[p] for p in ("lpv_inject", "lpv_downsample", "lpv_propagate", "lpv_merge", "lpv_lighting"))
            row = [ms["lpv_inject"], ms["geometry_volume"], ms["lpv_octree_geometry"], ms["lpv_downsample"],
                   ms["lpv_propagate"], ms["lpv_merge"], ms["lpv_lighting"], lpv_ms,
                   statistics.median(r[0] for r in runs) * 1000]
            octree = result.info.get("octree")
            iters = (f"{octree['iterations_per_level']}x{octree['levels']}" if octree else
                     "+".join(str(b["iterations"]) for b in result.info["cascades"][0]["bounces"]))
            errors = ""
            if ref is not None:
                mask = (ref.passes["Depth"][..., 0] < 1e9) & (result.passes["Depth"][..., 0] < 1e9)
                errors = "".join(f"{metrics.rel_l1(result.passes[p], ref.passes[p], mask):>{w}.3f}"
                                 for p, w in (("Diffuse Indirect", 10), ("Combined", 8)))
            print(f"{label:<21}{iters:>12}" + "".join(f"{v:>11.1f}" for v in row) + errors, flush=True)
            if octree:
                print(f"    cells per level {octree['level_cells']}, O_0 cells sampling level i: "
                      f"{octree['index_cells']}")
                print("    " + octree_errors(engine, settings.lpv, lpv_octree), flush=True)


def octree_errors(engine, settings, lpv_octree) -> str:
    """Olovsson and Doggett 2013, §4.1, after each iteration: re-run the propagation of the cached octree one step at a time."""
    def run(ctx):
        cache = engine.pipeline.cache
        tree, geo = cache.entries["lpv_downsample"].value, cache.entries["lpv_octree_geometry"].value
        out = []
        lpv_octree.propagate_levels(ctx, engine.pipeline.programs, tree, geo, settings,
                                    per_step=lambda step: out.append((step, *lpv_octree.octree_errors(tree))))
        return out
    rows = engine.worker.call(run)
    return "e_abs / e_rel per iteration: " + ", ".join(f"{k}: {a:.3g} / {r:.3f}" for k, a, r in rows)


if __name__ == "__main__":
    main()
