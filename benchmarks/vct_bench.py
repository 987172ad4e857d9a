# SPDX-License-Identifier: GPL-3.0-or-later
"""VCT time per pass and error against Cycles for example scenes, over grid size, image size and indirect_scale.
Prints a table (median of --repeats full re-renders after a warm-up render that compiles the shaders); asserts
nothing. Errors are rel-L1 over pixels that hit geometry, against the mean of two Cycles seeds (64 spp, 8 bounces
by default), with the reference's own noise floor (half the rel-L1 between its seeds) beside them. Glossy Indirect
is compared over the pixels where both Cycles' and our Glossy Color are non-zero (a scene of Diffuse BSDFs gets no
column; rough Principled surfaces above the cutoff count, with our 0); `glossy_cornell` is the Cornell box with a Principled floor of roughness 0.1.

    .venv/bin/python benchmarks/vct_bench.py [--scenes cornell spot_room courtyard glossy_cornell]
        [--grids 64 128] [--res 320x240 640x480] [--scales 1 2 4] [--bounces 8] [--samples 64] [--repeats 2]
"""
import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

PASSES = ("vct_voxelize", "vct_albedo", "vct_inject", "vct_mipmap", "vct_bounce", "vct_specular", "vct_trace",
          "vct_upsample")
EXTRA_SCENES = ("glossy_cornell",)


def build_scene(name):
    """An example scene (examples/scenes.py), or one of the benchmark's variants of them."""
    import bpy

    from examples import scenes

    if name == "glossy_cornell":
        scenes.build("cornell")
        floor = bpy.data.objects["Floor"]
        floor.data.materials.clear()
        floor.data.materials.append(scenes.principled_material("GlossyFloor", scenes.CORNELL_WHITE, 0.1))
        bpy.context.view_layer.update()
    else:
        scenes.build(name)


def parse_args():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scenes", nargs="+", default=["cornell", "spot_room", "courtyard"])
    parser.add_argument("--grids", nargs="+", type=int, default=[64, 128])
    parser.add_argument("--res", nargs="+", default=["320x240", "640x480"])
    parser.add_argument("--scales", nargs="+", type=int, default=[1], help="VctSettings.indirect_scale values")
    parser.add_argument("--specular", type=int, default=1, help="VctSettings.specular_cone (1 on, 0 off)")
    parser.add_argument("--bounces", type=int, default=None, help="VCT bounces (default: VctSettings' default)")
    parser.add_argument("--anisotropic", type=int, default=1, help="1: anisotropic volumes (default), 0: isotropic")
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples per seed (0: skip the errors)")
    parser.add_argument("--ref-bounces", type=int, default=8, help="Cycles bounces")
    parser.add_argument("--repeats", type=int, default=2)
    return parser.parse_args()


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


def error_columns(result, ref) -> str:
    """rel-L1 (and the reference's noise floor) of Diffuse Indirect, Combined and, where glossy, Glossy Indirect."""
    from bounce_gi.gpu_kernels.output import metrics

    if ref is None:
        return ""
    mask = (ref.passes["Depth"][..., 0] < 1e9) & (result.passes["Depth"][..., 0] < 1e9)
    errors = "".join(f"{metrics.rel_l1(result.passes[p], ref.passes[p], mask):>10.3f}"
                     f"{ref.noise_floor(p, mask):>8.3f} " for p in ("Diffuse Indirect", "Combined"))
    glossy = mask & (ref.passes["Glossy Color"].max(axis=-1) > 0) & \
        (result.passes["Glossy Color"].max(axis=-1) > 0)
    if glossy.any() and "Glossy Indirect" in ref.passes:
        errors += (f"{metrics.rel_l1(result.passes['Glossy Indirect'], ref.passes['Glossy Indirect'], glossy):>9.3f}"
                   f"{ref.noise_floor('Glossy Indirect', glossy):>8.3f}")
    return errors


def scene_rows(args, engine, name, res):
    """The table's rows of one scene at one image size: every grid and indirect_scale."""
    import bpy

    from bounce_gi.addon.extract import extract_scene
    from bounce_gi.addon.reference.cycles import ReferenceSettings, render_reference
    from bounce_gi.gpu_kernels.settings import RenderSettings
    from bounce_gi.gpu_kernels.vct.passes import pass_seconds
    from bounce_gi.gpu_kernels.vct.settings import VctSettings

    w, h = (int(v) for v in res.lower().split("x"))
    build_scene(name)
    scene = extract_scene(bpy.context.evaluated_depsgraph_get(), (w, h))
    ref = None
    if args.samples:
        ref = render_reference(scene.content_hash(), ReferenceSettings(w, h, samples=args.samples,
                                                                       bounces=args.ref_bounces))
    for grid in args.grids:
        for scale in args.scales:
            vs = VctSettings(resolution=grid, bounces=args.bounces, anisotropic=bool(args.anisotropic),
                             indirect_scale=scale, specular_cone=bool(args.specular))
            runs = timed_runs(engine, scene, RenderSettings("vct", w, h, vct=vs), args.repeats)
            total = statistics.median(r[0] for r in runs)
            result = runs[-1][1]
            times = [statistics.median(pass_seconds(r[1].timings, p) for r in runs) * 1000 for p in PASSES]
            print(f"{name:<15}{grid:>5}³{res:>9}{scale:>3}" + "".join(f"{t:>10.0f}" for t in times) +
                  f"{total * 1000:>9.0f}{result.info.get('fixup_pixels', 0):>6}" + error_columns(result, ref),
                  flush=True)


def main():
    args = parse_args()

    from bounce_gi.gpu_kernels.engine import Engine
    from bounce_gi.gpu_kernels.vct.settings import VctSettings

    if args.bounces is None:
        args.bounces = VctSettings().bounces
    engine = Engine()
    print(f"GL: {engine.gl_info()['renderer']}; VCT bounces {args.bounces}, "
          f"{'anisotropic' if args.anisotropic else 'isotropic'}, specular cone {'on' if args.specular else 'off'}; "
          f"Cycles {args.samples} spp x 2 seeds, {args.ref_bounces} bounces; times: median of {args.repeats} after "
          f"a warm-up (ms); fix = pixels traced again at full resolution by the upsampler")
    header = (f"{'scene':<15}{'grid':>6}{'image':>9}{'s':>3}" + "".join(f"{p[4:]:>10}" for p in PASSES) +
              f"{'total':>9}{'fix':>6}{'DI relL1':>10}{'(floor)':>8}{'Comb relL1':>11}{'(floor)':>8}"
              f"{'GlI relL1':>10}{'(floor)':>8}")
    print(header)
    for name in args.scenes:
        for res in args.res:
            scene_rows(args, engine, name, res)

if __name__ == "__main__":
    main()
