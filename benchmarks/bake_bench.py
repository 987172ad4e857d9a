# SPDX-License-Identifier: GPL-3.0-or-later
"""Bake GI to Color Attribute against Cycles' vertex bake: per-vertex rel-L1 and time, and Cycles' time at equal
error. Prints a Markdown table; asserts nothing.

For each scene: a two-seed Cycles vertex bake (DIFFUSE, INDIRECT only, colour off, 8 bounces; addon/reference/
vertex_bake.py) at --samples spp is the reference, with its noise floor (half the seeds' rel-L1). Cycles is then
baked at 4 ... 1024 spp (one seed) and its error and time measured; "Cycles at equal error" interpolates its time
log-log between the two sample counts whose errors bracket ours. Ours is the operator's blocking path with the
method at its Medium settings, timed from a cleared pass cache after a warm-up bake that compiled the shaders (so
the whole light transport is in the time, the shader compilation is not). `<scene>_dense` is the scene with every
face cut into a (cuts+1)² grid (bmesh), for a vertex count where Cycles' per-vertex cost shows.

    .venv/bin/python benchmarks/bake_bench.py [--scenes cornell spot_room courtyard cornell_dense] [--samples 4096]
        [--methods lpv vct] [--cuts 7]
"""
import argparse
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

LADDER = (4, 16, 64, 256, 1024)


def build(name, cuts):
    import bmesh
    import bpy

    from examples import scenes

    scenes.build(name.removesuffix("_dense"))
    if name.endswith("_dense"):
        for ob in [o for o in bpy.context.scene.objects if o.type == "MESH"]:
            bm = bmesh.new()
            bm.from_mesh(ob.data)
            bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=cuts, use_grid_fill=True)
            bm.to_mesh(ob.data)
            bm.free()
        bpy.context.view_layer.update()


def equal_error_seconds(ladder, error):
    """Cycles' seconds at `error`, log-log interpolated on the ladder [(spp, error, seconds)]; None outside it."""
    for (s0, e0, t0), (s1, e1, t1) in zip(ladder, ladder[1:]):
        if e1 <= error <= e0 and e0 > e1:
            f = math.log(e0 / error) / math.log(e0 / e1)
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    return None


def ours(scene, method):
    import bpy

    from bounce_gi.gpu_kernels.engine import get_engine
    from bounce_gi.ui import bake

    scene.bounce_gi.method, scene.bounce_gi.quality = method.upper(), "MEDIUM"
    bpy.ops.bounce_gi.bake_color_attribute()  # warm-up: shaders compiled
    get_engine().clear_cache()
    start = time.perf_counter()
    assert bpy.ops.bounce_gi.bake_color_attribute() == {"FINISHED"}
    seconds = time.perf_counter() - start
    out = {}
    for o in scene.objects:
        if o.type == "MESH":
            import numpy as np

            attr = o.data.color_attributes[bake.ATTRIBUTE]
            v = np.empty(len(attr.data) * 4, np.float32)
            attr.data.foreach_get("color", v)
            out[o.name] = v.reshape(-1, 4)[:, :3]
    return out, seconds


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", nargs="+", default=["cornell", "spot_room", "courtyard", "cornell_dense"])
    p.add_argument("--samples", type=int, default=4096)
    p.add_argument("--methods", nargs="+", default=["lpv", "vct"])
    p.add_argument("--cuts", type=int, default=7)
    args = p.parse_args()
    import bpy

    import bounce_gi
    from bounce_gi.addon.reference.vertex_bake import cycles_vertex_bake, rel_l1

    bounce_gi.register()
    print("| scene | vertices | method | rel-L1 | noise floor | ours s | Cycles s at equal error | "
          "Cycles ladder (spp: rel-L1 / s) |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.scenes:
        build(name, args.cuts)
        scene = bpy.context.scene
        meshes = [o for o in scene.objects if o.type == "MESH"]
        ref, seeds, _ = cycles_vertex_bake(meshes, args.samples)
        floor = 0.5 * rel_l1(seeds[0], seeds[1])
        ladder = []
        for spp in LADDER:
            values, _, seconds = cycles_vertex_bake(meshes, spp, seeds=(7,))
            ladder.append((spp, rel_l1(values, ref), seconds))
        text = ", ".join(f"{s}: {e:.3f} / {t:.2f}" for s, e, t in ladder)
        vertices = sum(len(o.data.vertices) for o in meshes)
        for method in args.methods:
            values, seconds = ours(scene, method)
            err = rel_l1(values, ref)
            eq = equal_error_seconds(ladder, err)
            eq_text = f"{eq:.2f} ({eq / seconds:.2g}x ours)" if eq else "outside the ladder"
            print(f"| {name} | {vertices} | {method} | {err:.3f} | {floor:.3f} | {seconds:.2f} | {eq_text} | {text} |",
                  flush=True)


if __name__ == "__main__":
    main()
