# SPDX-License-Identifier: GPL-3.0-or-later
"""The example scenes like users' (examples.scenes.USER_SCENES, issue 17) are what the issue asks for: Blender's
default Principled BSDF with a brass vase, metals, an image texture, sun and sky (strength 1, a constant colour), a
rug 1 mm above the floor, walls thinner than a voxel, a closed emissive lamp shade, >= 16 point lights, >= 100 m
outdoors, a product <= 10 cm, >= 20 objects. Read from the summary test_examples.py collects (conftest.py)."""
import importlib
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
USER_SCENES = importlib.import_module("examples.scenes").USER_SCENES  # the registry only: nothing is built here
DEFAULT_PRINCIPLED = {"Base Color": [0.8, 0.8, 0.8], "Roughness": 0.5, "Metallic": 0.0, "IOR": 1.5,
                      "Specular IOR Level": 0.5, "Emission Strength": 0.0}


@pytest.fixture(scope="module")
def sc(examples_summary):
    return examples_summary["scenes"]


def _extent(scene):
    """The scene's geometry's size along x, y, z (m)."""
    boxes = scene["meshes"].values()
    return [max(b["max"][i] for b in boxes) - min(b["min"][i] for b in boxes) for i in range(3)]


def test_at_least_twelve(sc):
    assert len(USER_SCENES) >= 12 and set(USER_SCENES) <= set(sc)


def test_materials(sc):
    """Blender's default Principled BSDF on every surface but the vase, which is brass (metallic 1); metals; a
    texture."""
    p = sc["default_principled"]["principled"]
    for mesh, info in sc["default_principled"]["meshes"].items():
        inputs = p[info["material"]]
        if mesh == "Vase":
            assert inputs["Metallic"] == 1.0 and inputs["Roughness"] == 0.5
        else:
            assert {k: pytest.approx(v) for k, v in DEFAULT_PRINCIPLED.items()} == inputs, mesh
    assert sum(v["Metallic"] == 1.0 for v in sc["metals"]["principled"].values()) >= 4
    assert "ShaderNodeTexImage" in sc["textured"]["node_types"]["Checker"]
    assert "ShaderNodeTexImage" in sc["furnished"]["node_types"]["Planks"]


def test_sun_and_sky(sc):
    sky_lit = {name for name in USER_SCENES if sc[name]["world_strength"] > 0}
    assert sky_lit == {"window_room", "thin_walls", "outdoor", "furnished"}
    for name in sky_lit:
        assert sc[name]["world_strength"] == 1.0 and not sc[name]["world_color_linked"], name  # a constant colour
        assert any(light["type"] == "SUN" for light in sc[name]["lights"].values()), name


def test_rug_and_thin_walls(sc):
    rug = sc["rug_room"]["meshes"]
    assert rug["Rug"]["min"][2] == pytest.approx(0.001) and rug["Rug"]["max"][2] == pytest.approx(0.001)
    assert rug["Floor"]["max"][2] == 0.0 and sc["rug_room"]["lights"]["Spot"]["type"] == "SPOT"
    walls = sc["thin_walls"]["meshes"]
    slabs = [m for name, m in walls.items() if name.startswith(("Partition", "WestWall", "EastWall"))]
    voxel = max(_extent(sc["thin_walls"])) / 64  # VCT's default 64³ grid, the finer of the two methods'
    thickness = [m["max"][0] - m["min"][0] for m in slabs]
    assert slabs and thickness == pytest.approx([0.02] * len(slabs), abs=1e-5) and max(thickness) < voxel


def test_lights(sc):
    shade = sc["lamp_room"]["meshes"]["LampShade"]
    assert shade["closed"] and shade["triangles"] == 92 and shade["material"] in sc["lamp_room"]["emissive"]
    assert not sc["lamp_room"]["lights"]  # the shade is the only light
    assert sum(light["type"] == "POINT" for light in sc["many_lights"]["lights"].values()) >= 16


def test_sizes(sc):
    assert max(_extent(sc["outdoor"])[:2]) >= 100.0
    assert max(_extent(sc["product_shot"])) <= 0.1 + 1e-6
    assert sum(t == "MESH" for t in sc["furnished"]["objects"].values()) >= 20
