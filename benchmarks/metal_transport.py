# SPDX-License-Identifier: GPL-3.0-or-later
"""How much light the metals example's metal objects add to the floor's and the back wall's Diffuse Indirect, ours
against Cycles: the scene as built, without its metal objects, and with them turned into diffuse surfaces of the
albedo our transport gives the metals (common/principled.transport_albedo). Both GI methods bounce a metal's
reflection as if it were diffuse with that albedo; the third variant tells what that costs against Cycles, which
reflects it in the mirror direction. Prints a table; asserts nothing.

    .venv/bin/python benchmarks/metal_transport.py [--samples 256] [--methods lpv vct] [--bounces 8]

A metal object's contribution to a surface = Σ Diffuse Indirect over that surface's pixels in the variant, minus the
same sum without the metals (only pixels that see the same point in both renders). Cycles at --samples × 2 seeds.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

VARIANTS = ("as built", "no metals", "diffuse, same albedo")
WALLS = ("Floor", "BackWall")


def build(variant):
    """The metals scene, its metal objects removed or made diffuse of the albedo a voxel gives them."""
    import bpy
    import numpy as np

    from bounce_gi.addon.extract import extract_scene
    from bounce_gi.gpu_kernels.common.principled import transport_albedo
    from examples import scenes

    scenes.build("metals")
    metal = [o for o in bpy.data.objects if o.type == "MESH" and o.name not in WALLS]
    if variant == "no metals":
        for ob in metal:
            bpy.data.objects.remove(ob)
    elif variant != "as built":
        extracted = {m.name: m for m in extract_scene(bpy.context.evaluated_depsgraph_get()).materials}
        for ob in metal:
            mat = ob.active_material.copy()
            scale, offset, _ = transport_albedo(extracted[ob.active_material.name])
            albedo = np.asarray(extracted[ob.active_material.name].base_color[:3]) * scale + offset
            bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
            bsdf.inputs["Metallic"].default_value = 0.0
            bsdf.inputs["Specular IOR Level"].default_value = 0.0
            bsdf.inputs["Base Color"].default_value = (*np.clip(albedo, 0.0, 1.0), 1.0)
            ob.active_material = mat


def render(variant, method, samples, bounces):
    """(ours, Cycles) Diffuse Indirect, shading normals and positions (H, W, 3) and the mask of hit pixels."""
    import bpy

    from bounce_gi.addon.cli import compare, parse_method_options, vct_options
    from bounce_gi.addon.extract import extract_scene

    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    build(variant)
    scene = extract_scene(bpy.context.evaluated_depsgraph_get())
    extra = [f"bounces={bounces}"] + (["gathered_bounces=0"] if bounces < 2 else [])
    _, ours, ref, mask = compare(scene, method, samples, bounces, progress=lambda m: None,
                                 lpv_options=parse_method_options(extra if method == "lpv" else []),
                                 vct_settings=vct_options(extra if method == "vct" else []))
    p = ours.passes
    return p["Diffuse Indirect"][..., :3], ref.passes["Diffuse Indirect"][..., :3], p["Normal"][..., :3], \
        p["Position"][..., :3], mask


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=256)
    parser.add_argument("--methods", nargs="+", default=["lpv", "vct"])
    parser.add_argument("--bounces", type=int, default=8)
    args = parser.parse_args()
    print(f"| method | variant | floor: ours | floor: Cycles | wall: ours | wall: Cycles |\n|---|---|---:|---:|---:|---:|")
    for method in args.methods:
        runs = {v: render(v, method, args.samples, args.bounces) for v in VARIANTS}
        _, _, normal0, position0, mask0 = runs["no metals"]
        for variant in VARIANTS[::2]:
            ours, ref, normal, position, mask = runs[variant]
            same = mask & mask0 & (abs(position - position0).sum(-1) < 1e-4)  # not hidden by a metal object
            cells = []
            for surface in (normal[..., 2] > 0.9, normal[..., 1] < -0.9):  # the floor, the back wall
                region = same & surface
                for img, base in ((ours, runs["no metals"][0]), (ref, runs["no metals"][1])):
                    cells.append(f"{float(img[region].sum() - base[region].sum()):.0f}")
            print(f"| {method} | {variant} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
