# SPDX-License-Identifier: GPL-3.0-or-later
"""The cached transport's receivers per axis (gpu_kernels/lpv/receivers.py), the clusters' partition cut
(clusters.partitioned) and the cells' crossing layers (lpv/crossings.py) — numpy only, no GL."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.common.grid import Grid
from bounce_gi.gpu_kernels.lpv import clusters as cl
from bounce_gi.gpu_kernels.lpv import crossings as cx
from bounce_gi.gpu_kernels.lpv import receivers as rv

pytestmark = pytest.mark.unit
FINE = Grid((0.0, 0.0, 0.0), 0.1, (6, 5, 4))


def test_the_index_finds_every_receiver_of_a_voxel_by_its_axis():
    """receiver_index packs 8 × the voxel's first receiver + the mask of its axes; lpv/lighting.glsl finds the
    receiver of axis a at first + (the mask's bits below a). Decoded here the same way, every receiver is found
    from its voxel and axis, and an empty voxel reads 0."""
    rng = np.random.default_rng(1)
    cells = np.stack([rng.integers(0, n, 40) for n in FINE.size], axis=1)
    axis = rng.integers(0, 3, 40)
    key = np.unique(np.concatenate([cells, axis[:, None]], axis=1), axis=0)  # one receiver per voxel and axis
    cells, axis = key[:, :3], key[:, 3]
    order = rv.receiver_order(cells, axis, FINE)
    cells, axis = cells[order], axis[order]
    index = rv.receiver_index(cells, axis, FINE)
    for r, ((x, y, z), a) in enumerate(zip(cells, axis)):
        entry = int(index[z, y, x])
        mask, first = entry & 7, entry >> 3
        assert mask >> a & 1
        assert first + bin(mask & ((1 << a) - 1)).count("1") == r
    occupied = np.zeros(FINE.size[::-1], bool)
    occupied[cells[:, 2], cells[:, 1], cells[:, 0]] = True
    assert (index[~occupied] == 0).all()


def test_neighbours_across_a_thin_wall_are_cut_apart():
    """A floor's receivers on either side of a wall standing on it (the wall's receiver shares their voxel) are not
    joined into one cluster; two floor receivers on the same side are."""
    cells = np.array([[1, 1, 0], [2, 1, 0], [2, 1, 0], [3, 1, 0]])
    normals = np.array([[0, 0, 1.0], [0, 0, 1.0], [1.0, 0, 0], [0, 0, 1.0]])
    wall_x = 0.255  # inside voxel 2, between the floor pieces' centroids there and in voxel 3
    positions = np.array([[0.15, 0.15, 0.0], [0.23, 0.15, 0.0], [wall_x, 0.15, 0.05], [0.35, 0.15, 0.0]])
    pairs = np.array([[0, 1], [1, 3]])
    cut = cl.partitioned(cells, normals, positions, pairs, FINE)
    assert cut.tolist() == [False, True]


def _cells_of(grid, pieces):
    """Fine voxel arrays (area, normal, Surfaces) of axis-aligned pieces [(fine voxel, axis, offset along it)]."""
    shape = tuple(2 * n + 2 for n in grid.size[::-1])
    area = np.zeros(shape + (4,))
    normal = np.zeros(shape + (4,))
    centroid = np.full(shape + (3,), 0.5)
    own = np.full(shape + (3,), np.nan)
    for (x, y, z), a, off in pieces:
        area[z, y, x, a] = area[z, y, x, 3] = 0.01
        normal[z, y, x, a] = 1.0
        centroid[z, y, x, a] = own[z, y, x, a] = off
    box = (np.zeros(shape + (3,)), np.ones(shape + (3,)))
    return area, normal, cx.Surfaces(centroid, own, *box)


def test_a_pillars_two_faces_in_one_cell_are_two_layers_a_curve_is_one():
    """Two y faces at either end of a cell (a pillar thinner than it) are two layers, each where its face is; faces
    that fill the range between (a curved surface) are one, at their mean; so are the voxels' centres when the
    surfaces' positions are unknown."""
    grid = Grid((0.0, 0.0, 0.0), 0.2, (2, 2, 2))
    # LPV cell (0, 0, 0) holds fine voxels 1..2 along each axis; fine voxel f's corner is at (f − 1)/2 cells.
    two = [((x, y, z), 1, off) for x in (1, 2) for z in (1, 2) for y, off in ((1, 0.1), (2, 0.9))]
    curve = [((x, y, z), 1, off) for x in (1, 2) for z, (y, off) in zip((1, 2), ((1, 0.1), (2, 0.9)))] + \
        [((1, 1, 1), 1, 0.9), ((2, 2, 2), 1, 0.1)]
    for pieces, layers in ((two, 2), (curve, 1)):
        area, normal, surfaces = _cells_of(grid, pieces)
        out = cx.crossing_layers(area, normal, grid, surfaces)
        assert out["coverage"][0, 0, 0, 3] < 0  # one plane's cell (crossings._pack): n, then (far, end, share, near)
        n = out["coverage"][0, 0, 0, :3]
        far, end, _, near = out["layers"][0, 0, 0]
        assert abs(n[1]) == pytest.approx(1.0) and (end < 0) == (layers == 2)
        if layers == 2:
            assert sorted(abs(v) for v in (near, far)) == pytest.approx([0.05, 0.95])
    plain = cx.crossing_layers(*_cells_of(grid, two)[:2], grid)
    assert plain["layers"][0, 0, 0, 1] > 0


def test_the_empty_space_distance_is_the_chebyshev_distance_to_the_nearest_surface_cell():
    """crossings.empty_distance against brute force on a random mask (and capped, and with no surface at all):
    lpv/gather.glsl skips distance − 1 cells on its strength, so one cell too many would let a ray pass a wall."""
    rng = np.random.default_rng(7)
    mask = rng.random((9, 7, 11)) < 0.02
    d = cx.empty_distance(mask, cap=16)
    cells = np.argwhere(mask)
    every = np.stack(np.meshgrid(*[np.arange(n) for n in mask.shape], indexing="ij"), -1).reshape(-1, 1, 3)
    brute = np.abs(every - cells[None]).max(axis=-1).min(axis=1).reshape(mask.shape)
    assert (d == np.minimum(brute, 16)).all()
    assert (cx.empty_distance(mask, cap=3) == np.minimum(brute, 3)).all()
    assert (cx.empty_distance(np.zeros((4, 4, 4), bool), cap=5) == 5).all()


def test_empty_cells_carry_their_distance_and_surface_cells_keep_their_planes():
    """mark_empty_space writes the distance into w of the cells lpv/gather.glsl reads as empty only: a plane cell's
    negative w (its coverage) and an axis cell's box code stay."""
    coverage = np.zeros((1, 1, 5, 4), np.float32)
    coverage[0, 0, 0] = (0.0, 0.0, 1.0, -0.8)  # a plane cell
    coverage[0, 0, 4] = (0.5, 0.0, 0.0, 1234.0)  # an axis cell and its box code
    cx.mark_empty_space(coverage)
    assert coverage[0, 0, :, 3].tolist() == pytest.approx([-0.8, 1.0, 2.0, 1.0, 1234.0])
