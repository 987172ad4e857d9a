# SPDX-License-Identifier: GPL-3.0-or-later
"""A receiver cut by a wall in its own voxel is kept on the side the wall faces (gpu_kernels/lpv/wall_sides.py) —
numpy only, no GL. One voxel of side 1 m; a floor receiver (axis z) over all of it, and walls standing on it. The
kept part is found on a 16 × 16 grid of the floor's box, so shares and centroids are exact to a sample (1/16)."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.lpv.wall_sides import clip_to_walls

pytestmark = pytest.mark.unit
SAMPLE = 1.0 / 16


def _receivers(walls):
    """The dict clip_to_walls reads: `walls` [(axis, canonical normal, facing, centroid, lo, hi)] then the floor,
    all in voxel (0, 0, 0), in receiver order (by axis)."""
    rows = sorted(walls, key=lambda w: w[0]) + [(2, (0, 0, 1), 1.0, (0.5, 0.5, 0.0), (0, 0, 0), (1, 1, 0))]
    return {"cells": np.zeros((len(rows), 3), np.int64), "axis": np.array([w[0] for w in rows]),
            "normals": np.array([w[1] for w in rows], np.float64), "areas": np.ones(len(rows)),
            "facing": np.array([w[2] for w in rows], np.float64),
            "positions": np.array([w[3] for w in rows], np.float64),
            "lo": np.array([w[4] for w in rows], np.float64), "hi": np.array([w[5] for w in rows], np.float64)}


def _wall_y(at, facing, x=(0.0, 1.0)):
    """A wall across y at y = `at` (facing −y: −1, +y: +1, both: 0), standing on the floor over x."""
    return (1, (0, 1, 0), facing, ((x[0] + x[1]) / 2, at, 0.5), (x[0], at, 0.0), (x[1], at, 1.0))


def _floor(r):
    out = clip_to_walls(r, 1.0)
    return out["areas"][-1], out["positions"][-1], out["lo"][-1], out["hi"][-1]


@pytest.mark.parametrize("facing, kept", [(-1.0, (0.0, 0.3)), (1.0, (0.3, 1.0))])
def test_the_floor_under_a_wall_is_kept_on_the_side_the_wall_faces(facing, kept):
    """A building's façade at y = 0.3 on a ground plane that goes on under it: the voxel's ground receiver keeps the
    part in front of the façade — its area, centroid and box those of that part (was: all of it, centred 0.2 from
    the façade's plane, on the inside when the façade faces −y)."""
    area, centroid, lo, hi = _floor(_receivers([_wall_y(0.3, facing)]))
    width = kept[1] - kept[0]
    assert area == pytest.approx(width, abs=SAMPLE)
    assert centroid[1] == pytest.approx((kept[0] + kept[1]) / 2, abs=SAMPLE / 2)
    assert (lo[1], hi[1]) == pytest.approx(kept, abs=SAMPLE)
    assert (centroid[0], lo[0], hi[0]) == pytest.approx((0.5, 0.0, 1.0))  # along the wall: all of it


def test_a_wall_facing_both_ways_or_ending_at_the_floors_edge_cuts_nothing():
    """A slab's two faces in the voxel face both ways (facing 0): either side is a room, nothing is dropped. A floor
    that ends where a wall stands (a room's floor at its wall) is all in front of it: unchanged."""
    for walls in ([_wall_y(0.3, 0.0)], [_wall_y(0.0, 1.0)], [_wall_y(1.0, -1.0)]):
        area, centroid, lo, hi = _floor(_receivers(walls))
        assert area == 1.0 and tuple(centroid) == (0.5, 0.5, 0.0) and tuple(hi) == (1, 1, 0)


def test_a_wall_that_ends_in_the_voxel_cuts_only_the_floor_behind_itself():
    """The wall, facing +y, stands over x in [0, 0.5] only (its end, a doorway's edge): the floor behind it beyond
    its end is open room, kept — 1 − 0.5 × 0.3 of the floor (its end reaches a twentieth of a voxel further: the
    extent's tolerance)."""
    area, centroid, _, _ = _floor(_receivers([_wall_y(0.3, 1.0, x=(0.0, 0.5))]))
    assert area == pytest.approx(1.0 - 0.5 * 0.3, abs=2 * SAMPLE)
    assert centroid[0] > 0.52 and centroid[1] > 0.55  # the kept part leans to the open side (0.545, 0.569)


def test_a_boxs_corner_keeps_the_floor_around_it():
    """A box's corner in the voxel: its −y face at y = 0.3 and its −x face at x = 0.4, each over its own side of the
    box. The floor outside the box (an L around the corner) is kept, the box's footprint (0.6 × 0.7) dropped."""
    minus_y = _wall_y(0.3, -1.0, x=(0.4, 1.0))
    minus_x = (0, (1, 0, 0), -1.0, (0.4, 0.65, 0.5), (0.4, 0.3, 0.0), (0.4, 1.0, 1.0))
    area, centroid, _, _ = _floor(_receivers([minus_y, minus_x]))
    assert area == pytest.approx(1.0 - 0.6 * 0.7, abs=2 * SAMPLE)
    assert centroid[0] < 0.4 and centroid[1] < 0.45
