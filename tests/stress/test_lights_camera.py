# SPDX-License-Identifier: GPL-3.0-or-later
"""Lights and cameras where users put them: none, many, inside geometry, degenerate sizes and angles; cameras
inside geometry, on a wall, looking straight up. Every case renders sanely (support/stress.check_sane)."""
from dataclasses import replace

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from support.stress import BLOCK, LIGHT_AT, METHODS, box_room, check_sane, light, settings

ALL = ("none",) + METHODS


def render(engine, scene, method, **kw):
    s = settings(method, **kw)
    result = engine.render(scene, s)
    check_sane(result, scene, s)
    return result


def light_passes(result):
    return [result.passes[n][..., :3] for n in ("Combined", "Diffuse Direct", "Diffuse Indirect", "Emission")]


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("kind", ("no lights", "zero power", "black light"))
def test_no_light_is_black(engine, method, kind):
    """Black, and with nothing to light it (no lamp with power, no emission, a black world) no GI pass runs: the
    method's passes are skipped and skipped_work says why."""
    lamp = light("POINT", 0.0 if kind == "zero power" else 100.0, LIGHT_AT)
    if kind == "black light":
        lamp = replace(lamp, color=(0.0, 0.0, 0.0))
    scene = box_room(lights=[] if kind == "no lights" else [lamp])
    result = render(engine, scene, method)
    assert all(p.max() == 0.0 for p in light_passes(result))
    assert not any(name.startswith(("lpv_", "vct_", "geometry_volume", "rsm")) for name in result.timings)
    if method != "none":
        assert any("nothing lights the scene" in w for w in result.info["skipped_work"])


SHAPES = {"square": {"shape": "SQUARE"}, "rectangle": {"shape": "RECTANGLE"}, "disk": {"shape": "DISK"},
          "ellipse": {"shape": "ELLIPSE"}}


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("shape", SHAPES)
def test_area_light_shapes(engine, method, shape):
    render(engine, box_room(lights=[light("AREA", 100.0, LIGHT_AT, **SHAPES[shape])]), method)


@pytest.mark.parametrize("method", ALL)
def test_an_area_light_of_zero_size_is_ignored_with_a_warning(engine, method):
    result = render(engine, box_room(lights=[light("AREA", 100.0, LIGHT_AT, name="flat", size=0.0)]), method)
    assert any("'flat'" in w and "zero size" in w for w in result.warnings), result.warnings
    assert all(p.max() == 0.0 for p in light_passes(result))


SPOTS = {"1 mrad cone": {"spot_size": 1e-3}, "180°": {"spot_size": np.pi}, "no blend": {"spot_blend": 0.0},
         "full blend": {"spot_blend": 1.0}}


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("spot", SPOTS)
def test_spot_cone_extremes(engine, method, spot):
    render(engine, box_room(lights=[light("SPOT", 100.0, LIGHT_AT, **SPOTS[spot])]), method)


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("radius", (1e-6, 5.0))
def test_point_light_radius_extremes(engine, method, radius):
    """A point light of radius 1 µm, or 5 m: a soft disk wider than the room."""
    render(engine, box_room(lights=[light("POINT", 100.0, LIGHT_AT, radius=radius)]), method)


def sun(direction):
    m = np.eye(4)
    m[:3, :3] = np.linalg.inv(cam.look_at((0, 0, 0), direction, (0, 1, 0) if abs(direction[2]) < 0.99 else
                                          (1, 0, 0)))[:3, :3]
    return replace(light("SUN", 3.0, (0, 0, 5)), matrix_world=m)


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("direction", ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0)),
                         ids=("horizon", "from below", "straight down"))
def test_sun_directions_on_an_open_room(engine, method, direction):
    scene = box_room(lights=[sun(direction)])
    ceiling = (np.abs(scene.positions[..., 2] - 2.0) < 1e-9).all(axis=1)
    scene = replace(scene, positions=scene.positions[~ceiling], normals=scene.normals[~ceiling],
                    uvs=scene.uvs[~ceiling], material_index=scene.material_index[~ceiling])
    render(engine, scene, method)


@pytest.mark.parametrize("method", ALL)
def test_256_lights(engine, method):
    """256 point lights of 1 W in a 16 × 16 array under the ceiling (the shadow atlas shrinks to fit them)."""
    xs = (np.arange(16) + 0.5) / 16 * 1.8 - 0.9
    lights = [light("POINT", 1.0, (x, y, 1.9), name=f"l{i}") for i, (x, y) in
              enumerate((x, y) for x in xs for y in xs)]
    result = render(engine, box_room(lights=lights), method)
    assert result.passes["Diffuse Direct"].max() > 0


@pytest.mark.parametrize("method", ALL)
def test_a_light_inside_the_closed_block_lights_nothing_outside(engine, method):
    centre = tuple((np.array(BLOCK[0]) + np.array(BLOCK[1])) / 2)
    result = render(engine, box_room(lights=[light("POINT", 100.0, centre)]), method)
    hit = result.passes["Depth"][..., 0] < 1e9
    assert lit_fraction(result) <= SHADOW_LEAK  # every visible pixel is outside the block
    # Light cannot leave the closed block. The voxel methods see the block's faces in voxels shared with the room
    # (the block is 1.5 LPV cells, 4.8 VCT voxels wide), so some leaks: bound below, measured in LEAK_INSIDE.
    indirect = float(result.passes["Diffuse Indirect"][hit].mean())
    lit = float(render(engine, box_room(), method).passes["Diffuse Indirect"][hit].mean())
    print(f"light inside the block {method}: indirect outside / lit room's {indirect / max(lit, 1e-30):.3f}")
    assert indirect <= LEAK_INSIDE[method] * max(lit, 1e-30)


# Indirect light outside the block / the lit room's: measured 0.37 (LPV 8³: the block is 1.5 cells wide, its faces
# share cells with the room) and 0.29 (VCT 16³); bound 0.5 for both, which a block that blocked nothing (≈ 1)
# fails.
LEAK_INSIDE = {"none": 0.0, "lpv": 0.5, "vct": 0.5}


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("where", ("on the floor", "on a wall corner", "outside the room", "just behind a wall"))
def test_lights_on_and_beyond_surfaces(engine, method, where):
    at = {"on the floor": (0.6, -0.6, 0.0), "on a wall corner": (1.0, 1.0, 2.0), "outside the room": (3, 0, 1),
          "just behind a wall": (1.5, 0.2, 1.2)}
    result = render(engine, box_room(lights=[light("POINT", 100.0, at[where])]), method)
    if where in ("outside the room", "just behind a wall"):
        assert lit_fraction(result) <= SHADOW_LEAK  # the closed room stays dark


# Pixels that direct light reaches through a closed surface, as a fraction of the 768: a light inside the block 1
# (a pixel on the block's silhouette that hits the inside of its top face: truly lit), a light behind a wall 2–3
# (within 5 mm of the corner where two walls meet). Bound 4 pixels. Before the cube face was chosen for the biased
# point (direct/eval.glsl) a light just behind a wall lit 6, and one inside the block 3.
SHADOW_LEAK = 4 / 768


def lit_fraction(result) -> float:
    return float((result.passes["Diffuse Direct"][..., :3].max(axis=-1) > 0).mean())


def camera_at(scene, eye, target, **kw):
    c2w = np.linalg.inv(cam.look_at(eye, target, (0, 0, 1) if abs(np.subtract(target, eye)[2]) < 0.99 *
                                    np.linalg.norm(np.subtract(target, eye)) else (0, 1, 0)))
    return replace(scene, camera=replace(scene.camera, matrix_world=c2w, **kw))


CAMERAS = {"inside the block": ((-0.07, 0.01, 0.5), (1, 0, 0.5), {}),
           "on the wall plane": ((1.0, 0.0, 1.0), (0, 0, 1), {}),
           "outside the room": ((3.0, -2.0, 1.5), (0, 0, 1), {}),
           "straight up": ((0.5, -0.5, 0.5), (0.5, -0.5, 2.0), {}),
           "straight down": ((0.5, -0.5, 1.8), (0.5, -0.5, 0.0), {}),
           "clip hides all": ((0.83, -0.87, 1.01), (0, 0, 1), {"clip_start": 50.0, "clip_end": 60.0}),
           "orthographic": ((0.83, -0.87, 1.01), (0, 0, 1), {"type": "ORTHO", "ortho_scale": 2.5}),
           "tiny clip range": ((0.83, -0.87, 1.01), (0, 0, 1), {"clip_start": 1e-6, "clip_end": 1e6})}


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("where", CAMERAS)
def test_cameras(engine, method, where):
    eye, target, kw = CAMERAS[where]
    result = render(engine, camera_at(box_room(), eye, target, **kw), method)
    if where == "clip hides all":
        assert (result.passes["Depth"][..., 0] >= 1e9).all() and result.passes["Combined"][..., :3].max() == 0
