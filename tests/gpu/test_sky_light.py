# SPDX-License-Identifier: GPL-3.0-or-later
"""The world as a light (common/lights.py: the sky light) against exact view factors, and closed rooms.

A 2 × 2 × 2 m room of one-sided quads facing in (as most users model rooms) with a 0.8 × 0.8 m skylight in its
roof, under a white world of radiance 1: a floor point's Diffuse Direct is exactly its view factor to the opening
(Cycles' DiffDir = E/π = L·F), since the room is convex and only the opening shows the sky. The same room closed:
no sky at all, though its walls are infinitely thin. Runs on llvmpipe (method "none": direct light only), 96 × 96.
"""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.synthetic import box_quads, patch_view_factor, quad, quad_scene

HOLE = 0.4  # half side of the skylight, centred in the roof at z = 2


def _room(skylight: bool):
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    h = HOLE if skylight else 0.0
    for x0, x1, y0, y1 in ((-1, 1, -1, -h), (-1, 1, h, 1), (-1, -h, -h, h), (h, 1, -h, h)):
        if x1 > x0 and y1 > y0:
            quads.append((quad([(x0, y0, 2), (x1, y0, 2), (x1, y1, 2), (x0, y1, 2)], (0, 0, -1)), 0))
    # Looking straight down from 1.9 m: the floor fills the view (lens 34 mm: about ±28°, ±1 m on the floor).
    return quad_scene(quads, [Material("white", (0.8, 0.8, 0.8))], [], (0.0, 0.001, 1.9), (0.0, 0.0, 0.0),
                      world=(1.0, 1.0, 1.0), lens=34.0)


@pytest.fixture(scope="module")
def engine():
    e = Engine()
    yield e
    e.shutdown()


def _floor(r):
    pos = r.passes["Position"]
    hit = (r.passes["Depth"][..., 0] < 1e9) & (np.abs(pos[..., 2]) < 1e-3)
    return pos[hit], r.passes["Diffuse Direct"][..., 0][hit]


def test_a_skylight_lights_the_floor_with_its_view_factor(engine):
    """Over the visible floor, Diffuse Direct against the exact view factor to the opening (patch_view_factor,
    mirrored: the opening seen from the floor is a floor patch seen from the roof). The sky's visibility is a
    quadrature over its directions (ShadowSettings.sky_directions): the opening (0.16 sr from the floor's centre)
    holds about five of them, so with one hard test per direction a point's value steps as the opening's edge
    crosses one (rel-L1 0.18), and each direction's shadow, dilated by a texel (direct/eval.glsl), darkens. The
    cells the opening's edge crosses are tested over their cones (direct/sky.glsl sky_soften) and the diffuse share
    then averaged over the penumbra (direct/sky_filter.glsl). Deterministic (no noise): measured mean 0.3% low,
    pixel rel-L1 0.035 (with hard tests and the filter: 5.9% low, 0.120); bounds 1.5% and 0.045 (the measurement +
    llvmpipe's rounding), so a quadrature that lost a cell's cone, went back to hard tests or doubled a direction's
    weight fails them."""
    pos, direct = _floor(engine.render(_room(True), RenderSettings("none", 96, 96)))
    assert len(pos) > 5000
    mirrored = np.column_stack([pos[:, 0], pos[:, 1], np.full(len(pos), 2.0)])
    exact = patch_view_factor(mirrored, np.tile((0.0, 0.0, -1.0), (len(pos), 1)), (-HOLE, HOLE, -HOLE, HOLE), 1.0,
                              m=40)
    mean_error = direct.mean() / exact.mean() - 1
    rel_l1 = np.abs(direct - exact).sum() / exact.sum()
    print(f"floor under a skylight: mean {direct.mean():.4f} vs exact {exact.mean():.4f} ({mean_error:+.3f}), "
          f"rel-L1 {rel_l1:.3f}")
    assert abs(mean_error) < 0.015
    assert rel_l1 < 0.045


def test_a_closed_room_of_one_sided_walls_keeps_the_sky_out(engine):
    """The same room with its roof closed: one-sided quads of zero thickness, and no direction of the sky reaches
    the floor. Measured: 1 of its 9216 pixels lit, 0.0305 (a corner pixel where three walls meet: one direction's
    hard test sees between two quads there, and the edge cells' cones around it, direct/sky.glsl sky_soften, spread
    that crack over their taps — 2 pixels at most 0.016 with hard tests alone); before each direction's shadow was
    dilated by a texel, 4% of the floor — the row along every wall — read 0.09-0.28. Bounds: 0.1% of the pixels,
    0.035. (The cone tracer's voxel visibility let the sky in through walls thinner than
    a voxel.)"""
    _, direct = _floor(engine.render(_room(False), RenderSettings("none", 96, 96)))
    assert len(direct) > 5000
    print("closed room: max floor Diffuse Direct", direct.max(), "share lit", (direct > 0).mean())
    assert (direct > 0).mean() < 0.001 and direct.max() < 0.035
