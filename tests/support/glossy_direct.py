# SPDX-License-Identifier: GPL-3.0-or-later
"""Glossy Direct against Cycles' (tests/accuracy/test_glossy_direct_vs_cycles.py runs this in a subprocess):

    python tests/support/glossy_direct.py SAMPLES [CASE ...]

Cases: "floor-<light>-<roughness>-<metallic>" — a 6 m Principled floor (base 0.8) seen at a glancing angle, lit by a
point light or a 0.5 m square area light — and "stage-<light>": the `principled` example (rough floor, glossy
sphere, half-metallic cube) lit by a sun, point, spot or area light. Direct light only on both sides (Cycles 0
bounces), so the comparison is of Glossy Direct alone. Prints one line "RESULT {json}": per case the rel-L1 of
Glossy Direct and its noise floor, and the ratio of the sums (ours / Cycles).
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", ".."))

from examples import scenes  # noqa: E402

FLOOR_CASES = [f"floor-{light}-{r}-{m}" for light in ("point", "area") for r in (0.2, 0.5, 0.8) for m in (0, 1)]
STAGE_CASES = [f"stage-{light}" for light in ("sun", "point", "spot", "area")]
CASES = FLOOR_CASES + STAGE_CASES


def build_floor(light: str, roughness: float, metallic: float) -> None:
    import bpy

    scenes.reset()
    scenes.set_world()
    mat = scenes.principled_material("Floor", (0.8, 0.8, 0.8), roughness, metallic)
    scenes.quad("Floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1), mat)
    scenes.camera((0.0, -4.0, 1.5), target=(0.0, 0.5, 0.0), lens=35.0)
    if light == "point":
        scenes.light("Lamp", "POINT", 300.0, (0.0, 1.5, 1.2), shadow_soft_size=0.0)
    else:
        scenes.light("Lamp", "AREA", 300.0, (0.0, 1.5, 1.2), rotation=(math.radians(20), 0, 0), shape="SQUARE",
                     size=0.5)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = scenes.RESOLUTION
    bpy.context.view_layer.update()


def build_stage(light: str) -> None:
    """The `principled` example with its sun replaced by `light` (the stage's own light placements)."""
    import bpy

    scenes.build("principled")
    bpy.data.objects.remove(bpy.data.objects["Sun"])
    if light == "sun":
        scenes.light("Sun", "SUN", 3.0, (0.0, 0.0, 5.0), rotation=scenes.SUN_ROTATION, angle=math.radians(0.5))
    elif light == "point":
        scenes.light("Point", "POINT", 500.0, scenes.POINT_LOCATION, shadow_soft_size=0.0)
    elif light == "spot":
        scenes.light("Spot", "SPOT", 800.0, scenes.SPOT_LOCATION, target=scenes.CUBE_LOCATION,
                     spot_size=math.radians(60.0), spot_blend=0.3, shadow_soft_size=0.0)
    else:
        scenes.light("Area", "AREA", 300.0, scenes.AREA_LOCATION, rotation=scenes.AREA_ROTATION, shape="SQUARE",
                     size=1.0)
    bpy.context.view_layer.update()


def build(case: str) -> None:
    parts = case.split("-")
    if parts[0] == "floor":
        build_floor(parts[1], float(parts[2]), float(parts[3]))
    else:
        build_stage(parts[1])


def main():
    import bpy

    from bounce_gi.addon.cli import compare
    from bounce_gi.addon.extract import extract_scene

    samples = int(sys.argv[1])
    out = {}
    for case in sys.argv[2:] or CASES:
        build(case)
        scene = extract_scene(bpy.context.evaluated_depsgraph_get())
        report, result, ref, mask = compare(scene, "none", samples, 0, progress=lambda m: None)
        ours, theirs = result.passes["Glossy Direct"][mask], ref.passes["Glossy Direct"][mask]
        out[case] = {"rel_l1": report["rel_l1"]["glossy_direct"], "noise_floor": report["noise_floor"]["glossy_direct"],
                     "sum_ratio": float(ours.sum() / theirs.sum()), "combined": report["rel_l1"]["combined"]}
    print("RESULT " + json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
