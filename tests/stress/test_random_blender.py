# SPDX-License-Identifier: GPL-3.0-or-later
"""Randomized scenes from a property-based generator (hypothesis) built in Blender, through the add-on's extraction,
to a render: what test_random.py checks of scenes built directly as the core's Scene, here with everything between
Blender and the core in the loop (evaluated meshes, object transforms, material nodes, light units, world, camera).

Each scene is real bpy data (support/random_bpy.py): 1–4 meshes (bmesh primitives, a from_pydata tetrahedron) with
their size in the mesh or in the object's scale, Principled / Diffuse / Emission materials of any colour,
roughness, metallic and emission strength, 0–3 lights of any type and power, a world colour or none, a perspective
or orthographic camera anywhere, optionally a closed room around it all, and every length × 10^-3 … 10^4 (point,
spot and area power × scale²). Drawn into the scenes too, what users get wrong: a zero-area face, a face duplicated
and flipped, and sometimes a NaN vertex, which must cost only its object (left out, a warning naming it, the rest
rendered). Every render, with none, LPV and VCT, must be sane (support/stress.check_sane), and the extracted scene
must hold what bpy itself counts (triangles per object) and the values set in Blender.
Derandomized (the same examples on every run, no example database written into the checkout), plus one explicit
example with every bad input; --stress-full runs five times as many.

bpy stays out of the pytest process (tests/conftest.py; it would import there, next to the engine, but its global
state would then reach every later test): one bpy subprocess for the module builds and extracts every scene, and
this process renders them with the suite's shared engine."""
import importlib.util

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings as hsettings, strategies as st

from support.random_bpy import BpyWorker
from support.stress import check_sane, settings

EXAMPLES, FULL_EXAMPLES = 5, 25

coord = st.floats(-2.0, 2.0, allow_nan=False)
xyz = st.tuples(coord, coord, coord)
angles = st.tuples(*[st.floats(-np.pi, np.pi)] * 3)
rgb = st.tuples(*[st.floats(0.0, 1.0)] * 3)
shape = st.fixed_dictionaries({
    "shape": st.sampled_from(("cube", "ico", "cylinder", "plane", "tetra")), "at": xyz,
    "size": st.tuples(*[st.floats(0.05, 3.0)] * 3), "rot": angles, "material": st.integers(0, 2),
    "inward": st.booleans(), "object_scale": st.booleans(), "smooth": st.booleans()})
material = st.fixed_dictionaries({
    "kind": st.sampled_from(("PRINCIPLED", "DIFFUSE", "EMISSION")), "color": rgb, "roughness": st.floats(0.0, 1.0),
    "metallic": st.floats(0.0, 1.0), "emission": st.one_of(st.just(0.0), st.floats(0.0, 5.0))})
lamp = st.fixed_dictionaries({
    "type": st.sampled_from(("POINT", "SPOT", "SUN", "AREA")), "power": st.floats(-3.0, 4.0), "at": xyz,
    "rot": angles, "color": rgb, "size": st.floats(0.0, 1.0), "size_y": st.floats(0.0, 1.0),
    "shape": st.sampled_from(("SQUARE", "RECTANGLE", "DISK", "ELLIPSE")), "spot": st.floats(0.02, 3.14),
    "blend": st.floats(0.0, 1.0), "angle": st.floats(0.0, 1.0)})
camera = st.fixed_dictionaries({"eye": xyz, "target": xyz, "ortho": st.booleans(), "lens": st.floats(10.0, 100.0)})
bad = st.fixed_dictionaries({"zero_area": st.booleans(), "doubled": st.booleans(), "at": xyz,
                             "nan": st.integers(0, 3).map(lambda i: i == 0)})  # a NaN vertex in one scene of four
scene_spec = st.fixed_dictionaries({
    "objects": st.lists(shape, min_size=1, max_size=4), "materials": st.lists(material, min_size=1, max_size=3),
    "lights": st.lists(lamp, max_size=3), "world": st.one_of(st.none(), rgb), "camera": camera,
    "room": st.booleans(), "scale": st.floats(-3.0, 4.0), "bad": bad})

# Every bad input at once, whatever hypothesis draws: a lit Cornell-like room at 1 km with a NaN-vertex cube in it.
EVERY_BAD_INPUT = {
    "objects": [{"shape": "cube", "at": (0.3, -0.2, -1.0), "size": (1.0, 0.8, 1.5), "rot": (0.0, 0.0, 0.4),
                 "material": 1, "inward": False, "object_scale": True, "smooth": False}],
    "materials": [{"kind": "DIFFUSE", "color": (0.7, 0.7, 0.7), "roughness": 0.0, "metallic": 0.0, "emission": 0.0},
                  {"kind": "PRINCIPLED", "color": (0.8, 0.3, 0.1), "roughness": 0.4, "metallic": 0.5,
                   "emission": 0.0}],
    "lights": [{"type": "POINT", "power": 3.0, "at": (0.0, 0.0, 2.0), "rot": (0.0, 0.0, 0.0), "color": (1, 1, 1),
                "size": 0.1, "size_y": 0.1, "shape": "SQUARE", "spot": 1.0, "blend": 0.1, "angle": 0.0}],
    "world": (0.05, 0.05, 0.05), "room": True, "scale": 3.0,
    "camera": {"eye": (2.0, -2.0, 1.0), "target": (0.0, 0.0, -0.5), "ortho": False, "lens": 30.0},
    "bad": {"zero_area": True, "doubled": True, "at": (-1.0, 0.5, -0.5), "nan": True}}


@pytest.fixture(scope="module")
def blender(tmp_path_factory):
    if importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy not installed in this interpreter")
    worker = BpyWorker(tmp_path_factory.mktemp("random_bpy"))
    yield worker
    worker.close()


def broken_objects(counted) -> list:
    return sorted(name for name, ok in counted["finite"].items() if not ok)


def check_extraction(scene, counted, spec) -> None:
    """The extraction holds what bpy counts: every finite mesh object's triangles, no NaN-vertex object's, one
    warning naming each of those and none naming another, every light, only finite positions."""
    broken = broken_objects(counted)
    assert broken == (["Broken"] if spec["bad"]["nan"] else []), broken
    kept = sum(n for name, n in counted["triangles"].items() if name not in broken)
    assert scene.triangle_count == kept, (scene.triangle_count, counted)
    assert np.isfinite(scene.positions).all()
    for name in counted["triangles"]:
        named = [w for w in scene.warnings if f"'{name}'" in w and "NaN" in w]
        assert len(named) == (name in broken), (name, scene.warnings)
    assert [l.name for l in scene.lights] == [f"Light{i}" for i in range(len(spec["lights"]))]


def check_values(scene, spec) -> None:
    """The materials used and the lights hold the values set in Blender (float32 rounding): colours, roughness,
    metallic, emission colour × strength; power × scale² for point, spot and area lights, a sun's strength as is."""
    s = 10.0 ** spec["scale"]
    mats = {m.name: m for m in scene.materials}
    for i, m in enumerate(spec["materials"]):
        got = mats.get(f"Mat{i}")  # only the materials of the objects extracted are there
        if got is None:
            continue
        base = (0.0, 0.0, 0.0) if m["kind"] == "EMISSION" else m["color"]
        emission = (0.0, 0.0, 0.0) if m["kind"] == "DIFFUSE" else np.multiply(m["color"], m["emission"])
        assert np.allclose(got.base_color, base, atol=1e-6) and np.allclose(got.emission, emission, rtol=1e-6,
                                                                               atol=1e-6), (got, m)
        if m["kind"] == "PRINCIPLED":
            assert np.allclose((got.roughness, got.metallic), (m["roughness"], m["metallic"]), atol=1e-6), (got, m)
    for light, lamp in zip(scene.lights, spec["lights"]):
        power = 10.0 ** lamp["power"] * (1.0 if lamp["type"] == "SUN" else s * s)
        assert light.type == lamp["type"] and light.power == pytest.approx(power, rel=1e-6), (light, lamp)
        assert np.allclose(light.color, lamp["color"], atol=1e-6), (light, lamp)


@pytest.mark.parametrize("method", ("none", "lpv", "vct"))
def test_random_blender_scenes_extract_and_render_sanely(engine, blender, full, method):
    @hsettings(max_examples=FULL_EXAMPLES if full else EXAMPLES, deadline=None, database=None, derandomize=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(scene_spec)
    @example(EVERY_BAD_INPUT)
    def check(spec):
        scene, counted = blender.extract(spec)
        check_extraction(scene, counted, spec)
        check_values(scene, spec)
        s = settings(method)
        result = engine.render(scene, s)
        check_sane(result, scene, s)
        hit = int((result.passes["Depth"][..., 0] < 1e9).sum())
        print(f"random bpy scene {method} ×10^{spec['scale']:.2f}: {scene.triangle_count} triangles, lights "
              f"{[l.type for l in scene.lights]}, {hit} pixels hit, left out {broken_objects(counted)}")
        for name in broken_objects(counted):  # the render says what it left out, by the object's name
            assert any(f"'{name}'" in w for w in result.warnings), (name, result.warnings)

    check()
