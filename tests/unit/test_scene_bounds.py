# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene.bounds is found once per positions array: the same answer each time, a new one for new positions, and
nothing of it in the scene's hash or its copies."""
import dataclasses

import numpy as np

from support.synthetic import lit_patch_scene


def test_bounds_follow_the_positions_array_and_stay_out_of_the_hash():
    scene = lit_patch_scene("wall beside")
    key = scene.content_hash()
    corners = scene.positions.reshape(-1, 3).astype(np.float64)
    lo, hi = scene.bounds()
    assert np.array_equal(lo, corners.min(axis=0)) and np.array_equal(hi, corners.max(axis=0))
    lo[:] = 99.0  # a caller changing what it was given changes nothing kept
    assert np.array_equal(scene.bounds()[0], corners.min(axis=0))
    assert scene.content_hash() == key
    moved = dataclasses.replace(scene, positions=scene.positions + np.float32([0.0, 0.0, 2.5]))
    assert np.array_equal(moved.bounds()[1], corners.max(axis=0) + [0.0, 0.0, 2.5])
    scene.positions = scene.positions * np.float32(2.0)  # replaced, as an edit replaces it
    assert np.array_equal(scene.bounds()[0], corners.min(axis=0) * 2.0)
    empty = dataclasses.replace(scene, positions=np.zeros((0, 3, 3), np.float32))
    assert all(np.array_equal(b, np.zeros(3)) for b in empty.bounds())
