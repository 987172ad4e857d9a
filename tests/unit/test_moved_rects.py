# SPDX-License-Identifier: GPL-3.0-or-later
"""What an object's move redraws and re-makes: the rectangles its box covers in the shadow and RSM views
(direct/shadows.moved_rects) and the RSM records merged from the kept ones and those of the redrawn blocks
(lpv/gather.merge_records), and the texels of those rectangles a redraw changed (direct/shadows.changed_views). The
GPU side, against cold renders: tests/gpu/test_light_edits.py, tests/gpu/test_sky_update.py and
tests/gpu/test_lpv_transfer_update.py."""
import numpy as np

from bounce_gi.gpu_kernels.common.lights import cube_views
from bounce_gi.gpu_kernels.direct.shadows import MOVED_MARGIN, changed_views, moved_rects
from bounce_gi.gpu_kernels.lpv.gather import VPL_DTYPE, covered_blocks, merge_records


def _one_view(view, box, tile):
    """The rectangle of one view, written plainly: the box's corners in front of the near plane (z ≥ −w in clip
    space) and the points where its edges cross that plane, projected one by one."""
    m = np.asarray(view.view_projection, np.float64)
    corners = {(i, j, k): m @ np.array([box[i][0], box[j][1], box[k][2], 1.0])
               for i in (0, 1) for j in (0, 1) for k in (0, 1)}
    pts = [c for c in corners.values() if c[2] + c[3] >= 0]
    for (i, j, k), c in corners.items():
        for other in ((1, j, k), (i, 1, k), (i, j, 1)):
            if other == (i, j, k):
                continue
            d = corners[other]
            fa, fb = c[2] + c[3], d[2] + d[3]
            if (fa >= 0) != (fb >= 0):
                pts.append(c + (d - c) * fa / (fa - fb))
    pts = np.array([p[:2] / p[3] for p in pts if p[3] > 0])
    if len(pts) == 0:
        return None
    tx, ty, tw, th = tile
    lo = np.maximum(np.floor([tx + (pts[:, 0].min() * 0.5 + 0.5) * tw, ty + (pts[:, 1].min() * 0.5 + 0.5) * th])
                    - MOVED_MARGIN, [tx, ty])
    hi = np.minimum(np.ceil([tx + (pts[:, 0].max() * 0.5 + 0.5) * tw, ty + (pts[:, 1].max() * 0.5 + 0.5) * th])
                    + MOVED_MARGIN, [tx + tw, ty + th])
    if np.any(hi <= lo):
        return None
    return int(lo[0]), int(lo[1]), int(hi[0] - lo[0]), int(hi[1] - lo[1])


def test_every_views_rectangle_is_the_one_its_own_projection_gives():
    """Random boxes against a cube's six faces from random eyes (boxes beside, around and behind the eye): the
    views projected together give each view's rectangle exactly as projecting that view alone does."""
    rng = np.random.default_rng(3)
    tiles = [(64 * i, 32, 64, 64) for i in range(6)]
    seen = set()
    for _ in range(300):
        views = cube_views(rng.normal(0, 2, 3), 64, 0.01, 20.0)
        lo = rng.normal(0, 2, 3)
        box = np.stack([lo, lo + rng.uniform(0.01, 1.5, 3)])
        got = moved_rects(views, box, tiles)
        want = [_one_view(v, box, t) for v, t in zip(views, tiles)]
        assert got == want
        seen.update("none" if r is None else "whole" if r == tuple(t) else "part" for r, t in zip(got, tiles))
    assert seen == {"none", "part"}
    # A box around the eye covers every face whole; one beside it, reaching behind a face's eye plane, covers that
    # face only where it lies in front (before the near-plane clip: the whole tile, so an object moved beside a
    # lamp redrew all of its faces).
    views = cube_views(np.zeros(3), 64, 0.01, 20.0)
    assert moved_rects(views, np.array([[-1.0, -1, -1], [1, 1, 1]]), tiles) == [tuple(t) for t in tiles]
    beside = np.array([[-0.2, -0.2, 0.5], [0.2, 0.5, 1.0]])   # in front of +z, across +y's and −y's eye planes
    rects = moved_rects(views, beside, tiles)
    assert rects == [_one_view(v, beside, t) for v, t in zip(views, tiles)]
    parts = [r for r, t in zip(rects, tiles) if r is not None]
    assert len(parts) == 2 and all(r != tuple(t) for r, t in zip(rects, tiles))


def test_merged_records_are_the_kept_ones_outside_the_redrawn_blocks_and_the_new_ones_inside():
    """An atlas of 16 × 8 blocks (k = 2 texels), two planes a block: records kept from before everywhere, then two
    rectangles redrawn with new records (some blocks now empty, some with records where there were none): the merge
    holds exactly the new records inside the rectangles' blocks and the old ones elsewhere, in slot order."""
    rng = np.random.default_rng(8)
    k, blocks_x, blocks_y = 2, 16, 8

    def records(slots, tag):
        r = np.zeros(len(slots), VPL_DTYPE)
        r["flux"][:, 0], r["flux"][:, 1] = tag, slots
        return r
    old_slots = np.sort(rng.choice(2 * blocks_x * blocks_y, 150, replace=False))
    rects = [(4, 2, 6, 4), (20, 10, 5, 3)]  # atlas texels: blocks x 2..4, y 1..2 and x 10..12, y 5..6
    inside = np.zeros((blocks_y, blocks_x), bool)
    inside[1:3, 2:5] = inside[5:7, 10:13] = True
    candidates = np.nonzero(np.repeat(inside.ravel(), 2))[0]
    new_slots = np.sort(rng.choice(candidates, len(candidates) // 2, replace=False))
    redone = covered_blocks(rects, k, (blocks_x, blocks_y))
    assert np.array_equal(redone, inside.ravel())
    got, slots = merge_records((records(old_slots, 1.0), old_slots), (records(new_slots, 2.0), new_slots), redone)
    in_new = np.repeat(inside.ravel(), 2)
    want = np.sort(np.concatenate([old_slots[~in_new[old_slots]], new_slots]))
    assert np.array_equal(slots, want) and np.array_equal(got["flux"][:, 1], want)
    assert np.array_equal(got["flux"][:, 0], np.where(in_new[want], 2.0, 1.0))


def test_changed_views_cut_each_rectangle_to_the_texels_that_changed():
    """shadows.changed_views: a rectangle whose kept texels were compared becomes the box of those that changed, a
    view none of whose texels changed drops out, and a view drawn whole or not compared stays as it was."""
    from types import SimpleNamespace

    kept = SimpleNamespace(changed={0: (12, 14, 15, 16), 1: None})
    maps = SimpleNamespace(redrawn=[(0, (10, 10, 8, 8)), (1, (30, 30, 4, 4)), (2, None), (3, (50, 50, 2, 2))],
                           overwritten=kept)
    assert changed_views(maps) == [(0, (12, 14, 3, 2)), (2, None), (3, (50, 50, 2, 2))]
    maps.overwritten = None  # nothing kept (too many texels): every rectangle as it was drawn
    assert changed_views(maps) == maps.redrawn
