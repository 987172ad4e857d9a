# SPDX-License-Identifier: GPL-3.0-or-later
"""A light's edit redoes that light's work only: its shadow maps (direct/shadows.render_depth), its RSM views
(lpv/rsm.render_rsm), its first bounce (lpv/passes.first_bounce) and its Diffuse and Glossy Direct
(direct/lighting.light_groups) are redrawn, re-binned and re-lit beside what the other lights kept, the sky's
visibility is kept when another light moves, and a power edit re-lights nothing — and every pass is still exactly
what a cold render of the edited scene gives."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.common.lights import ShadowSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from support.synthetic import box_quads, quad, quad_scene

PASSES = ("Diffuse Direct", "Diffuse Indirect", "Glossy Direct", "Combined")


def point(name, x, y, z, power=40.0):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return Light(name, "POINT", (1.0, 0.9, 0.8), power, m)


def area(name, x, y, z, power=60.0, size=0.5):
    """A square light facing down: its soft shadows read the raw depth atlas (direct/eval.glsl patch_visibility)."""
    m = np.eye(4)  # Blender's area lights shine along their local −z
    m[:3, 3] = (x, y, z)
    return Light(name, "AREA", (0.8, 0.9, 1.0), power, m, shape="SQUARE", size=size)


def scene(lights):
    """A floor and a box under a point light, an area light and a grey sky."""
    floor = quad([(-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)], (0, 0, 1))
    quads = [(floor, 0)] + box_quads((-0.5, -0.5, 0.0), (0.5, 0.5, 1.0), 1, inward=False)
    s = quad_scene(quads, [Material("floor", (0.6, 0.6, 0.6)), Material("box", (0.8, 0.3, 0.2))], lights,
                   eye=(0.0, -7.0, 6.0), target=(0.0, 0.0, 0.0), world=(0.2, 0.2, 0.2))
    s.resolution = (96, 72)
    return s


def test_moving_one_light_redraws_only_its_work_and_matches_a_cold_render(engines):
    from bounce_gi.gpu_kernels.settings import RenderSettings

    warm, cold = engines
    settings = RenderSettings(method="lpv", width=96, height=72, shadow=ShadowSettings(
        cube_resolution=128, sky_directions=64, sky_resolution=64))
    lights = [point("a", -2.0, -1.0, 3.0), area("b", 2.0, 1.5, 2.5)]
    warm.render(scene(lights), settings)
    entries = warm.pipeline.cache.entries
    cubes = {0: 6, 1: 6 * 4}  # the point light's cube, the area light's 2 × 2 sample points' cubes
    views = entries["shadow_depth"].value.drawn
    assert views == cubes[0] + cubes[1] + 64 and entries["rsm"].value.drawn == views  # and the sky's maps
    assert entries["lpv_inject"].value.binned == 3 and entries["direct_light"].value["relit"] == 3
    for moved in (0, 1, "power"):
        make = (point, area)[1 if moved == "power" else moved]
        if moved == "power":  # a brighter light: the same images, rescaled
            lights[1] = make(lights[1].name, *lights[1].matrix_world[:3, 3], power=2.0 * lights[1].power)
        else:
            lights[moved] = make(lights[moved].name, lights[moved].matrix_world[0, 3] + 0.3, 0.2, 2.8)
        edited = scene(lights)
        result = warm.render(edited, settings)
        if moved == "power":
            assert {"shadow_depth", "rsm", "lpv_inject"} <= set(result.skipped)
        else:
            assert entries["shadow_depth"].value.drawn == cubes[moved]  # the moved light's cubes only
            assert entries["rsm"].value.drawn == cubes[moved]
            assert entries["lpv_inject"].value.binned == 1
        assert entries["direct_light"].value["relit"] == (0 if moved == "power" else 1)
        assert "sky_visibility" in result.skipped
        fresh = cold.render(edited, settings)
        cold.clear_cache()
        for name in PASSES:
            np.testing.assert_array_equal(result.passes[name], fresh.passes[name], err_msg=name)


def _maps(engine, method) -> list:
    """The engine's shadow depth atlas and, for the LPV, its RSM's targets, read back."""
    entries = engine.pipeline.cache.entries
    textures = [entries["shadow_depth"].value.texture]
    if method == "lpv":
        rsm = entries["rsm"].value
        textures += [rsm.position, rsm.normal, rsm.albedo]
    return engine.worker.call(lambda _ctx: [np.frombuffer(t.read(), np.float32).copy() for t in textures])


@pytest.mark.parametrize("method", ["none", "lpv"])
def test_moving_an_object_keeps_the_emitters_and_sky_views_while_the_bounds_hold(engines, method):
    """The sky's shadow views and the emitters' lights (light_sources) depend on the emissive triangles and the
    scene's bounds (common/lights.static_key), not on where a non-emitting object stands inside them: moving the box
    keeps them, redraws in each depth map and RSM view only the rectangle the box's old and new places cover
    (direct/shadows.moved_rects), and the maps and Diffuse Direct are still exactly a cold render's; lifting it
    above everything else grows the bounds, and they are made again."""
    from bounce_gi.gpu_kernels.settings import RenderSettings

    warm, cold = engines
    settings = RenderSettings(method=method, width=96, height=72, shadow=ShadowSettings(
        cube_resolution=128, sky_directions=64, sky_resolution=64))
    lights = [point("a", -2.0, -1.0, 3.0)]
    base = scene(lights)
    warm.render(base, settings)
    for lift, kept in ((0.0, True), (4.0, False)):
        moved = scene(lights)
        box = moved.material_index == 1
        moved.positions = moved.positions.copy()
        moved.positions[box] += np.float32([0.3, 0.2, lift])
        result = warm.render(moved, settings)
        assert ("light_sources" in result.skipped) == kept and "shadow_depth" not in result.skipped
        entries = warm.pipeline.cache.entries
        partial = [entries[name].value.partial for name in ("shadow_depth", "rsm")[:2 if method == "lpv" else 1]]
        assert all((p > 0) == kept for p in partial)  # grown bounds move every sky view: each is drawn whole
        fresh = cold.render(moved, settings)
        for a, b in zip(_maps(warm, method), _maps(cold, method)):
            np.testing.assert_array_equal(a, b)
        cold.clear_cache()
        np.testing.assert_array_equal(result.passes["Diffuse Direct"], fresh.passes["Diffuse Direct"])


def test_an_object_move_relights_only_the_pixels_it_can_change(engines):
    """After a box's move, Diffuse and Glossy Direct are lit again only where the move can change them
    (direct/lighting.Relight): the pixels its old and new places cover, and those whose shadow tests read a texel
    the depth atlas redrew, as far as a test reads (the point light's PCF, the area light's blocker search, the
    sun's). The rest keep their values, and every pass is still exactly what a cold render gives: a reach too short
    (the area light's search left out) leaves stale soft shadows beside the box, and this comparison fails."""
    from bounce_gi.gpu_kernels.settings import RenderSettings

    warm, cold = engines
    settings = RenderSettings(method="lpv", width=96, height=72, shadow=ShadowSettings(
        cube_resolution=128, sky_directions=64, sky_resolution=64))
    sun = np.eye(4)
    sun[:3, :3] = [[1, 0, 0], [0, 0.8, -0.6], [0, 0.6, 0.8]]  # tilted 37° about x
    lights = [point("a", -2.0, -1.0, 3.0), area("b", 1.0, 0.5, 2.0, size=1.5),
              Light("sun", "SUN", (1.0, 1.0, 0.9), 2.0, sun, angle=0.05)]
    warm.render(scene(lights), settings)
    for step in (1, 2):
        moved = scene(lights)
        box = moved.material_index == 1
        moved.positions = moved.positions.copy()
        moved.positions[box] += np.float32([0.15 * step, 0.1 * step, 0.0])
        result = warm.render(moved, settings)
        direct = warm.pipeline.cache.entries["direct_light"].value
        # some pixels kept (the sky's group, which reads the sky's shares, is lit again whole, and counts as 1)
        assert 0.0 < direct["relit_pixels"] < 1.0, direct["relit_pixels"]
        fresh = cold.render(moved, settings)
        cold.clear_cache()
        for name in PASSES:
            np.testing.assert_array_equal(result.passes[name], fresh.passes[name], err_msg=name)
