# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV: a surface covered by another one 1 mm away (a rug on a floor) lends the bounce none of its colour.

A closed white room with a red rug lying 1 mm over its whole floor, lit by a spot near the ceiling that reaches the
rug and the far wall. The far wall's indirect light comes from the rug (its own lit part does not light itself), so
its colour is the rug's, green/red = 0.1/0.7 = 0.1429, after any number of bounces (the white walls leave the ratio
alone; light that met the rug twice is redder still).
- The RSM saw the floor through the rug in patches while it compared projective depth, whose steps at a few metres
  are about a millimetre (near = far / 10⁴, common/lights._near_far); it compares the radial distance now, linear
  like the shadow maps' (lpv/rsm.glsl). One bounce: 0.279 before, 0.1429 since.
- The voxels the rug lies in keep an albedo per side (voxel/voxelize.py sides=True): the room's side reflects the
  rug's colour, the floor's underside the floor's. Three bounces: 0.1519 with one albedo per voxel (the floor
  whitens every bounce after the first), 0.1426 since.
The render is deterministic and the answer exact, so the bound is the rug's ratio plus 1.5% (0.145): float32 sums
and the LPV's leaks at the room's corners, and below both faults' values.
"""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.synthetic import box_quads, quad, quad_scene

RUG = (0.7, 0.1, 0.05)


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _spot_over_a_rug():
    """A closed white room 4 x 4 x 2.6 m, a red rug over its whole floor, the spot near the ceiling."""
    m = np.linalg.inv(cam.look_at((0.0, -0.6, 2.55), (0.0, 0.4, 0.0), (0, 0, 1)))  # local −Z toward the rug
    spot = Light("spot", "SPOT", (1, 1, 1), 800.0, m, spot_size=math.radians(60.0), spot_blend=0.2)
    rug = quad([(-2, -2, 0.001), (2, -2, 0.001), (2, 2, 0.001), (-2, 2, 0.001)], (0, 0, 1))
    room = box_quads((-2, -2, 0), (2, 2, 2.6), 0)
    return quad_scene(room + [(rug, 1)], [Material("white", (0.8,) * 3), Material("rug", RUG)],
                      [spot], (-0.3, -1.85, 1.5), (0.2, 0.6, 0.4), lens=18.0)


@pytest.mark.parametrize("bounces", [1, 3])
def test_a_rug_on_a_floor_bounces_its_own_colour(engine, bounces):
    r = engine.render(_spot_over_a_rug(), RenderSettings("lpv", 80, 60, lpv=LpvSettings(resolution=32,
                                                                                           bounces=bounces)))
    di, pos = r.passes["Diffuse Indirect"], r.passes["Position"]
    hit = r.passes["Depth"][..., 0] < 1e9
    on_wall = hit & (np.abs(pos[..., 1] - 2.0) < 1e-3) & (pos[..., 2] > 0.3)  # the far wall
    wall = di[on_wall]
    ratio = float(wall[:, 1].sum() / wall[:, 0].sum())
    print(f"bounces {bounces}: wall green/red {ratio:.4f} (rug {RUG[1] / RUG[0]:.4f}) over {on_wall.sum()} pixels")
    assert on_wall.sum() > 200
    assert ratio < 0.145


def test_a_material_edit_reuses_the_front_most_image_and_gives_a_cold_render(engine):
    """A material edit voxelises only the edited material's share of each receiver side (lpv/receivers.py
    current_albedo), reading the front-most image kept with the geometry volume (lpv/occlusion.KEEP_FRONT_BYTES)
    instead of rasterising it again: the recoloured rug's bounce must be what a fresh engine renders, to the
    update's rounding (tests/gpu/test_lpv_material_edit.py: 1e-5 of the albedo; measured here 8.6e-7 of the mean
    after three bounces, bound 1e-5), and blue now."""
    settings = RenderSettings("lpv", 80, 60, lpv=LpvSettings(resolution=32, bounces=3))
    engine.render(_spot_over_a_rug(), settings)
    blue = _spot_over_a_rug()
    blue.materials[1] = Material("rug", (0.05, 0.2, 0.6))
    warm = engine.render(blue, settings)
    assert "geometry_volume" in warm.skipped and "lpv_albedo" not in warm.skipped
    cold_engine = Engine()
    try:
        cold = cold_engine.render(blue, settings)
    finally:
        cold_engine.shutdown()
    a, b = warm.passes["Diffuse Indirect"], cold.passes["Diffuse Indirect"]
    print(f"warm vs cold: max |Δ| {np.abs(a - b).max() / b.mean():.1e} of the mean")
    assert np.abs(a - b).max() <= 1e-5 * float(b.mean())
    di = warm.passes["Diffuse Indirect"][warm.passes["Depth"][..., 0] < 1e9]
    assert di[:, 2].sum() > 2.0 * di[:, 0].sum()  # the blue rug's light
