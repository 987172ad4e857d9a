# SPDX-License-Identifier: GPL-3.0-or-later
"""Timings on a machine without Blender (a GPU box): the VCT and LPV pass tables of vct_bench.py / lpv_bench.py,
from scenes exported here, errors against the Cycles references exported with them.

Two steps, because bpy (Python 3.13, ~300 MB) cannot travel to a GPU machine but a pickled `Scene` can:

    .venv/bin/python benchmarks/device_bench.py export DIR [--samples 128]   # here: examples → DIR (pkl + npz)
    python3 benchmarks/device_bench.py run DIR [--only tables|incremental] [--log FILE]   # there

`run` needs numpy and moderngl, and this checkout importable as `bounce_gi` (e.g. a symlink named bounce_gi in a
folder on PYTHONPATH). It prints one line per configuration as soon as it is measured (so a run cut short still
reports), each the median of --repeats full re-renders after a warm-up that compiles the shaders (the pass cache
is cleared before each, so every pass runs), then the cost of one update after each kind of edit with the cache
kept. rel-L1 columns are over pixels that hit geometry, against the mean of two Cycles seeds, as in
vct_bench.py. Asserts nothing. benchmarks/results/h200/ holds one run.
"""
import argparse
import os
import pickle
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

SCENES = ("cornell", "spot_room", "courtyard")
RESOLUTIONS = ((320, 240), (640, 480))
ERROR_RES = (320, 240)  # references are exported at this size only (they travel: 3 passes × 3 scenes ≈ 8 MB)
REF_PASSES = ("Diffuse Indirect", "Combined", "Depth")
VCT_PASSES = ("vct_voxelize", "vct_albedo", "vct_inject", "vct_mipmap", "vct_bounce", "vct_specular", "vct_trace",
              "vct_upsample")
LPV_PASSES = ("rsm", "lpv_inject", "geometry_volume", "lpv_propagate", "lpv_lighting")
OCTREE_CONFIGS = (("uniform k=16", dict(max_iterations=16, epsilon=0.0)), ("octree L=3 k=4", dict(octree_levels=3,
                                                                                                  octree_iterations=4)))
OCTREE_PASSES = ("lpv_octree_geometry", "lpv_inject", "lpv_downsample", "lpv_propagate", "lpv_merge", "lpv_lighting")


def export(out_dir, samples):
    import bpy

    from bounce_gi.addon.reference.cycles import ReferenceSettings, render_reference
    from bounce_gi.addon.extract import extract_scene
    from examples import scenes

    os.makedirs(out_dir, exist_ok=True)
    for name in SCENES:
        scenes.build(name)
        for w, h in RESOLUTIONS:
            scene = extract_scene(bpy.context.evaluated_depsgraph_get(), (w, h))
            with open(os.path.join(out_dir, f"{name}_{w}x{h}.pkl"), "wb") as f:
                pickle.dump(scene, f)
            if (w, h) == ERROR_RES:
                ref = render_reference(scene.content_hash(), ReferenceSettings(w, h, samples=samples, bounces=8))
                np.savez(os.path.join(out_dir, f"{name}_{w}x{h}_ref.npz"),
                         **{p.replace(" ", "_"): ref.passes[p].astype(np.float32) for p in REF_PASSES})
        print(f"exported {name}", flush=True)


def _load(scene_dir, name, w, h):
    with open(os.path.join(scene_dir, f"{name}_{w}x{h}.pkl"), "rb") as f:
        scene = pickle.load(f)
    ref = None
    path = os.path.join(scene_dir, f"{name}_{w}x{h}_ref.npz")
    if os.path.exists(path):
        data = np.load(path)
        ref = {p: data[p.replace(" ", "_")] for p in REF_PASSES}
    return scene, ref


def _timed(engine, scene, settings, repeats):
    """(median seconds, runs) of lpv_bench's warm-up-then-repeat timing."""
    from benchmarks.lpv_bench import timed_runs

    runs = timed_runs(engine, scene, settings, repeats)
    return statistics.median(r[0] for r in runs), runs


def _errors(result, ref):
    from bounce_gi.gpu_kernels.output import metrics

    if ref is None:
        return ""
    mask = (ref["Depth"][..., 0] < 1e9) & (result.passes["Depth"][..., 0] < 1e9)
    return "".join(f"{metrics.rel_l1(result.passes[p], ref[p], mask):>11.3f}" for p in ("Diffuse Indirect",
                                                                                         "Combined"))


def run(engine, scene_dir, grids, lpv_grids, repeats, say):
    from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
    from bounce_gi.gpu_kernels.settings import RenderSettings
    from bounce_gi.gpu_kernels.vct.passes import pass_seconds
    from bounce_gi.gpu_kernels.vct.settings import VctSettings

    say(f"\nVCT (defaults: {VctSettings().bounces} bounces, {VctSettings().gathered_bounces} gathered)")
    say(f"{'scene':<11}{'grid':>6}{'image':>9}" + "".join(f"{p[4:]:>10}" for p in VCT_PASSES) +
        f"{'total':>9}{'DI relL1':>11}{'Comb relL1':>11}")
    for name in SCENES:
        for w, h in RESOLUTIONS:
            scene, ref = _load(scene_dir, name, w, h)
            for grid in grids:
                settings = RenderSettings("vct", w, h, vct=VctSettings(resolution=grid))
                total, runs = _timed(engine, scene, settings, repeats)
                times = [statistics.median(pass_seconds(r[1].timings, p) for r in runs) * 1000 for p in VCT_PASSES]
                say(f"{name:<11}{grid:>5}³{f'{w}x{h}':>9}" + "".join(f"{t:>10.1f}" for t in times) +
                    f"{total * 1000:>9.1f}" + _errors(runs[-1][1], ref))
    say("\nLPV (3 bounces, adaptive iterations)")
    say(f"{'scene':<11}{'grid':>6}{'casc':>5}{'iters':>7}" + "".join(f"{p:>16}" for p in LPV_PASSES) +
        f"{'total':>9}{'DI relL1':>11}{'Comb relL1':>11}")
    for name in SCENES:
        w, h = ERROR_RES
        scene, ref = _load(scene_dir, name, w, h)
        for grid in lpv_grids:
            for cascades in (1, 3):
                settings = RenderSettings("lpv", w, h, lpv=LpvSettings(resolution=grid, cascades=cascades,
                                                                       bounces=3))
                total, runs = _timed(engine, scene, settings, repeats)
                times = [statistics.median(r[1].timings.get(p, 0.0) for r in runs) * 1000 for p in LPV_PASSES]
                iters = sum(c["iterations"] for c in runs[-1][1].info["cascades"])
                say(f"{name:<11}{grid:>5}³{cascades:>5}{iters:>7}" + "".join(f"{t:>16.1f}" for t in times) +
                    f"{total * 1000:>9.1f}" + _errors(runs[-1][1], ref))
    say("\nOctree LPV (Olovsson and Doggett 2013, Table 1) against the uniform grid, 32³, 3 bounces")
    say(f"{'scene':<11}{'config':<18}{'propagate':>11}{'LPV total':>11}{'frame':>9}{'DI relL1':>11}{'Comb relL1':>11}")
    for name in SCENES:
        w, h = ERROR_RES
        scene, ref = _load(scene_dir, name, w, h)
        for label, cfg in OCTREE_CONFIGS:
            settings = RenderSettings("lpv", w, h, lpv=LpvSettings(resolution=32, bounces=3, **cfg))
            total, runs = _timed(engine, scene, settings, repeats)
            ms = {p: statistics.median(r[1].timings.get(p, 0.0) for r in runs) * 1000 for p in OCTREE_PASSES}
            lpv_ms = sum(ms[p] for p in OCTREE_PASSES if p.startswith("lpv_"))
            say(f"{name:<11}{label:<18}{ms['lpv_propagate']:>11.1f}{lpv_ms:>11.1f}{total * 1000:>9.1f}" +
                _errors(runs[-1][1], ref))


def _edited(scene, kind, sign):
    """A copy of `scene` after one small edit (addon/bench/incremental.py's kinds, applied to the extracted scene)."""
    import copy

    out = copy.deepcopy(scene)
    step = sign * 0.05  # metres, as addon/bench/incremental.STEP
    if kind == "camera_only":
        out.camera.matrix_world[0, 3] += step
    elif kind == "light_move":
        out.lights[0].matrix_world[0, 3] += step
    elif kind == "material_change":
        m = out.materials[0]
        m.base_color = tuple(min(1.0, c + 0.5 * step) for c in m.base_color)
    return out


def incremental(engine, scene_dir, repeats, say):
    """Median seconds of one update after an edit in a long-lived engine (pass cache kept), per kind."""
    from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
    from bounce_gi.gpu_kernels.settings import RenderSettings
    from bounce_gi.gpu_kernels.vct.settings import VctSettings

    kinds = ("unchanged", "camera_only", "light_move", "material_change")
    say("\nIncremental updates (pass cache kept; median of %d edits, alternately +0.05 and −0.05), ms" % repeats)
    say(f"{'scene':<11}{'method':<14}{'full':>9}" + "".join(f"{k:>17}" for k in kinds))
    w, h = ERROR_RES
    for name in SCENES:
        scene, _ = _load(scene_dir, name, w, h)
        for label, settings in (("vct 64³", RenderSettings("vct", w, h, vct=VctSettings())),
                                ("lpv 32³", RenderSettings("lpv", w, h, lpv=LpvSettings()))):
            full, _ = _timed(engine, scene, settings, repeats)
            row = []
            for kind in kinds:
                variants = [scene if kind == "unchanged" else _edited(scene, kind, s) for s in (1, -1)]
                times = []
                for i in range(repeats + 1):
                    start = time.perf_counter()
                    engine.render(variants[i % 2], settings)
                    times.append(time.perf_counter() - start)
                row.append(statistics.median(times[1:]))
            say(f"{name:<11}{label:<14}{full * 1000:>9.1f}" + "".join(f"{t * 1000:>17.1f}" for t in row))


def main():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("export")
    p.add_argument("dir")
    p.add_argument("--samples", type=int, default=128, help="Cycles samples per seed")
    p = sub.add_parser("run")
    p.add_argument("dir")
    p.add_argument("--grids", nargs="+", type=int, default=[64, 128, 256])
    p.add_argument("--lpv-grids", nargs="+", type=int, default=[32, 64])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--log", default=os.devnull, help="also write the table here")
    p.add_argument("--only", choices=("tables", "incremental"), help="run one part")
    args = parser.parse_args()
    if args.cmd == "export":
        export(args.dir, args.samples)
    else:
        with open(args.log, "w") as log:
            def say(line=""):
                print(line, flush=True)
                log.write(line + "\n")
                log.flush()

            from bounce_gi.gpu_kernels.engine import Engine

            engine = Engine()  # one context: the incremental part reuses the compiled shaders
            say(f"GL: {engine.gl_info()['renderer']}; median of {args.repeats} after a warm-up; ms")
            if args.only != "incremental":
                run(engine, args.dir, args.grids, args.lpv_grids, args.repeats, say)
            if args.only != "tables":
                incremental(engine, args.dir, args.repeats, say)


if __name__ == "__main__":
    main()
