# SPDX-License-Identifier: GPL-3.0-or-later
"""Principled BSDF sweep: one sphere per (Specular IOR Level, IOR, roughness, metallic), our Diffuse Color and
Glossy Color against Cycles' (tests/accuracy/test_principled_vs_cycles.py runs this in a subprocess):

    python tests/support/principled_sweep.py SAMPLES

Prints one line "RESULT {json}": per combination, the fraction of its sphere's pixels whose Diffuse Color and Glossy
Color are within 0.01 (every channel) of Cycles', and the largest difference.
"""
import itertools
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", ".."))

import numpy as np  # noqa: E402

from examples import scenes  # noqa: E402

LEVELS = (0.0, 0.25, 0.5, 1.0)
IORS = (1.0, 1.33, 1.5, 2.5)
ROUGHNESS = (0.0, 0.5, 1.0)
METALLIC = (0.0, 0.5, 1.0)
BASE = (0.8, 0.45, 0.2)  # coloured, so a channel mix-up or the metal's F0 shows
CELL_PX = 24  # pixels per sphere cell
TOLERANCE = 0.01


def combinations():
    return list(itertools.product(LEVELS, IORS, ROUGHNESS, METALLIC))


def build():
    """The sweep scene: spheres of radius 0.45 on a unit grid, seen from above by an orthographic camera."""
    import bpy

    scenes.reset()
    scenes.set_world()
    combos = combinations()
    cols = 12
    rows = -(-len(combos) // cols)
    for k, (level, ior, rough, metal) in enumerate(combos):
        mat = scenes.principled_material(f"m{k}", BASE, rough, metal)
        bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        bsdf.inputs["IOR"].default_value = ior
        bsdf.inputs["Specular IOR Level"].default_value = level
        scenes.uv_sphere(f"s{k}", 0.45, (k % cols + 0.5, k // cols + 0.5, 0.0), mat, segments=48, rings=24)
    cam = scenes.camera((cols / 2, rows / 2, 5.0), rotation=(0.0, 0.0, 0.0))
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = float(max(cols, rows))
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = cols * CELL_PX, rows * CELL_PX
    scene.render.resolution_percentage = 100
    bpy.context.view_layer.update()
    return cols, rows


def main():
    import bpy

    from bounce_gi.addon.cli import compare
    from bounce_gi.addon.extract import extract_scene

    samples = int(sys.argv[1])
    cols, rows = build()
    scene = extract_scene(bpy.context.evaluated_depsgraph_get())
    report, result, ref, mask = compare(scene, "none", samples, 0, progress=lambda m: None)
    out = {}
    for name in ("Diffuse Color", "Glossy Color"):
        diff = np.abs(result.passes[name] - ref.passes[name]).max(axis=-1)
        for k, combo in enumerate(combinations()):
            # Pass images are top-down; the grid's y grows upwards.
            row = rows - 1 - k // cols
            cell = (slice(row * CELL_PX, (row + 1) * CELL_PX),
                    slice((k % cols) * CELL_PX, (k % cols + 1) * CELL_PX))
            d, m = diff[cell], mask[cell]
            entry = out.setdefault(",".join(str(v) for v in combo), {})
            key = name.split()[0].lower()
            entry[key] = float(np.mean(d[m] <= TOLERANCE))
            entry[key + "_max"] = float(d[m].max())
    print("RESULT " + json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
