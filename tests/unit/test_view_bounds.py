# SPDX-License-Identifier: GPL-3.0-or-later
"""A lamp's shadow views through a small change of the scene's bounds (common/lights.py FAR_STEP): an object moved
at the scene's edge must not change every lamp's views, or the update draws every map and RSM again."""
import numpy as np

from bounce_gi.gpu_kernels.common.lights import build_light_buffers
from support.synthetic import room_with_box


def _cube(scene):
    buffers = build_light_buffers(scene)
    return [v for v, light in zip(buffers.views, buffers.view_lights) if light == 0]


def test_a_lamps_views_keep_through_a_small_growth_of_the_bounds_and_always_hold_the_scene():
    """The room's box lifted 1 … 50 mm through the room's open top (2 m): the bulb's cube views stay those of the
    room as it was until the far plane must grow, and the far plane always reaches the farthest corner of the
    scene; lifted 60 cm it grows."""
    base = _cube(room_with_box(0.0, size=0.3))
    kept = 0
    for lift in (0.001, 0.005, 0.01, 0.02, 0.05, 0.6):
        scene = room_with_box(1.7 + lift, size=0.3)  # the box's top at 2 m + lift
        views = _cube(scene)
        corners = np.asarray(scene.positions, np.float64).reshape(-1, 3)
        reach = np.linalg.norm(corners - np.asarray(views[0].origin), axis=1).max()
        assert all(v.far >= reach for v in views)
        same = all(np.array_equal(a.view_projection, b.view_projection) for a, b in zip(base, views))
        kept += same
        assert same or lift >= 0.05
    assert kept >= 4 and not same  # small lifts keep the views, the last does not
