# SPDX-License-Identifier: GPL-3.0-or-later
"""What a geometry edit counts as changed for the cached transport's update (gpu_kernels/lpv/transfer_update.py):
the LPV cells whose visibility planes changed, and the few boxes cut around them that segments are tested against.
The update's result against a render from scratch: tests/gpu/test_lpv_transfer.py."""
import numpy as np

from bounce_gi.gpu_kernels.common.grid import Grid
from bounce_gi.gpu_kernels.lpv import crossings
from bounce_gi.gpu_kernels.lpv import transfer_update as tu


def _slab(lo, hi):
    """Every cell (N, 3) xyz of the box lo..hi (inclusive)."""
    axes = [np.arange(a, b + 1) for a, b in zip(lo, hi)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def _inside(cells, box):
    return np.all((cells >= box[0]) & (cells <= box[1]), axis=1)


def test_a_lifted_blocks_top_and_bottom_get_a_box_each_not_one_around_both():
    """Two solid slabs 8 cells apart (a block lifted: its top and bottom changed): two boxes, each exactly one slab
    — one box around both held four times the cells."""
    cells = np.concatenate([_slab((5, 5, 1), (15, 15, 2)), _slab((5, 5, 10), (15, 15, 11))])
    groups = tu.split_cells(cells, tu.MAX_BOXES)
    boxes = sorted((tuple(g.min(axis=0)), tuple(g.max(axis=0))) for g in groups)
    assert boxes == [((5, 5, 1), (15, 15, 2)), ((5, 5, 10), (15, 15, 11))]


def test_the_boxes_hold_every_cell_and_are_at_most_the_most_asked_for():
    """Scattered cells: at most `most` groups, which partition the cells, and whose boxes hold no more cells in all
    than one box around them; a solid block stays one."""
    rng = np.random.default_rng(3)
    cells = np.unique(rng.integers(0, 40, (300, 3)), axis=0)
    for most in (1, 3, 8):
        groups = tu.split_cells(cells, most)
        assert 1 <= len(groups) <= most
        together = np.concatenate(groups)
        assert len(together) == len(cells) and len(np.unique(together, axis=0)) == len(cells)
        held = sum(np.prod(g.max(axis=0) - g.min(axis=0) + 1) for g in groups)
        assert held <= np.prod(cells.max(axis=0) - cells.min(axis=0) + 1)
        assert all(_inside(g, (g.min(axis=0), g.max(axis=0))).all() for g in groups)
    assert len(tu.split_cells(_slab((0, 0, 0), (4, 4, 4)), 8)) == 1


def test_changed_boxes_span_whole_cells_in_world_space():
    """changed_boxes: world-space corners of each group's cells, from the grid's origin and cell."""
    grid = Grid((1.0, -2.0, 0.5), 0.25, (16, 16, 16))
    boxes = tu.changed_boxes(np.array([[2, 3, 4]]), grid)
    assert np.allclose(boxes, [[[1.5, -1.25, 1.5], [1.75, -1.0, 1.75]]])
    assert tu.changed_boxes(np.zeros((0, 3), np.int64), grid) is None


def test_changed_cells_are_the_moved_voxels_cells_and_those_whose_planes_changed():
    """A moved fine voxel names its LPV cell (fine voxels 2c + 1 and 2c + 2); a plane moved by more than the
    tolerance names its cell; one moved by float rounding does not; nor does an empty cell whose distance to the
    nearest surface (crossings.mark_empty_space) changed."""
    shape = (6, 6, 6, 4)
    before = {name: np.zeros(shape, np.float32) for name in crossings.FIELDS}
    before["coverage"][1, 2, 3] = (0.0, 0.0, 1.0, -1.0)  # a plane cell (negative w): cell xyz (3, 2, 1)
    before["layers"][1, 2, 3] = (1.5, 1.5, 1.0, 1.5)
    before["coverage"][4, 4, 4] = (0.0, 0.0, 1.0, -1.0)
    before["layers"][4, 4, 4] = (4.5, 1.5, 1.0, 4.5)
    before["coverage"][0, 0, 0, 3] = 3.0  # an empty cell: its distance to a surface
    crossings.mark_empty_space(before["coverage"])
    after = {name: a.copy() for name, a in before.items()}
    after["layers"][1, 2, 3, 0] += 0.01  # moved: changed
    after["layers"][4, 4, 4, 0] += 1e-6  # rounding: the same
    after["coverage"][0, 0, 0, 3] = 5.0
    cells = tu.changed_cells(np.array([[5.0, 1.0, 2.0]]), before, after)  # fine voxel (5, 1, 2) → cell (2, 0, 0)
    assert sorted(map(tuple, cells)) == [(2, 0, 0), (3, 2, 1)]
    assert len(tu.changed_cells(np.zeros((0, 3)), before, before)) == 0
