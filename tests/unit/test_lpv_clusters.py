# SPDX-License-Identifier: GPL-3.0-or-later
"""The cached LPV transport's bookkeeping (gpu_kernels/lpv/clusters.py, transfer.py), without a GPU: clusters, the binning of
VPL flux into them, and the factored bounce series against the series computed bounce by bounce."""
from types import SimpleNamespace

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common.grid import Grid
from bounce_gi.gpu_kernels.lpv import clusters as cl
from bounce_gi.gpu_kernels.lpv import transfer as tr
from bounce_gi.gpu_kernels.lpv.gather import VPL_DTYPE

FINE = Grid((0.0, 0.0, 0.0), 0.1, (40, 40, 40))


def _plane(axis, index, lo, hi, sign=1.0):
    """Voxels of an axis plane at fine index `index` spanning [lo, hi) on the other two axes; normals ±axis."""
    u, w = (axis + 1) % 3, (axis + 2) % 3
    a, b = np.meshgrid(np.arange(lo[0], hi[0]), np.arange(lo[1], hi[1]), indexing="ij")
    cells = np.zeros((a.size, 3), np.int64)
    cells[:, axis], cells[:, u], cells[:, w] = index, a.ravel(), b.ravel()
    normals = np.zeros((a.size, 3))
    normals[:, axis] = sign
    return cells, normals


def _scene(*planes):
    cells = np.concatenate([p[0] for p in planes])
    normals = np.concatenate([p[1] for p in planes])
    return cells, normals, np.full(len(cells), 0.01)


def _records(points, normals, flux):
    rec = np.zeros(len(points), VPL_DTYPE)
    rec["position"][:, :3], rec["position"][:, 3] = points, 1.0
    rec["normal"][:, :3] = normals
    rec["flux"][:, :3] = flux
    return rec


def test_clusters_fit_the_budget_keep_floor_and_wall_apart_and_skip_sides_facing_nothing():
    """A floor (z index 0) and a wall (x index 0) of a room, 4 × 4 m: every inward side belongs to a cluster of
    its own orientation, areas add up, at most `budget` clusters; the outward sides have the whole scene behind
    them (faces_something) and get none."""
    cells, normals, areas = _scene(_plane(2, 0, (0, 0), (40, 40)), _plane(0, 0, (0, 1), (40, 40)))
    c = cl.make_clusters(cells, normals, areas, FINE, budget=64)
    assert c.count <= 64
    inward = c.side_cluster[:, 0]  # the front side: +z for the floor, +x for the wall
    assert (inward >= 0).all() and (c.side_cluster[:, 1] < 0).all()
    cluster_normal = c.records["normal"][inward, :3]
    assert np.allclose(cluster_normal, normals)  # no cluster mixes the floor with the wall
    assert c.records["normal"][:, 3].sum() == pytest.approx(areas.sum(), rel=1e-6)


def test_two_rooms_floors_in_one_block_stay_apart_and_keep_their_flux():
    """Two floors in one plane, separated by a partition (two wall-voxel columns that belong to no floor): no
    cluster spans both, so flux binned from the left floor stays on the left (two rooms lit independently)."""
    left = _plane(2, 5, (0, 0), (13, 40))
    right = _plane(2, 5, (15, 0), (40, 40))
    wall = _plane(0, 13, (5, 0), (40, 40)), _plane(0, 14, (5, 0), (40, 40))
    cells, normals, areas = _scene(left, right, *wall)
    c = cl.make_clusters(cells, normals, areas, FINE, budget=40)
    assert 12 // c.block == 15 // c.block  # a block holds both floors: only the connectivity keeps them apart
    floor = c.records["normal"][:, 2] > 0.99
    lo, hi = c.box[floor, 0, 0], c.box[floor, 1, 0]  # x extent of each floor cluster's voxels
    assert ((hi < 1.3) | (lo > 1.5)).all()
    rng = np.random.default_rng(3)
    points = np.c_[rng.uniform(0.0, 1.25, 500), rng.uniform(0.0, 4.0, 500), np.full(500, 0.55)]
    flux, escaped = cl.bin_flux(c, _records(points, np.tile((0, 0, 1.0), (500, 1)), rng.uniform(0, 1, (500, 3))))
    assert escaped == 0 and flux[:, 0].sum() > 0
    lit = flux[:, 0] > 0
    assert (c.box[lit, 1, 0] < 1.3).all()


def test_flux_on_a_side_facing_nothing_leaves_the_scene():
    """A sunlit roof's top (the scene's highest surface, facing up): its light reaches no receiver — it is
    counted as escaped, not moved onto another surface."""
    cells, normals, areas = _scene(_plane(2, 0, (0, 0), (40, 40)), _plane(2, 30, (0, 0), (40, 40)))
    c = cl.make_clusters(cells, normals, areas, FINE, budget=64)
    top = np.c_[np.full(10, 2.0), np.full(10, 2.0), np.full(10, 3.05)]
    flux, escaped = cl.bin_flux(c, _records(top, np.tile((0, 0, 1.0), (10, 1)), np.ones((10, 3))))
    assert flux.sum() == 0 and escaped == pytest.approx(30.0)


def test_flux_on_a_walls_outside_stays_out_however_near_an_inside_surface_faces_its_way():
    """A room's back wall (y index 30, one-sided, its inside facing −y) with a sofa's back in the voxel row inside
    it (y index 29, its voxels' mean normal mostly +y, toward the wall, and a little up: the sofa's top shares
    them): both in one block, on the same side key (+y). A sunlit record on the
    wall's outside (facing +y, in the wall's voxel) is outside the room: nothing lies before it, so it leaves the
    scene — it must not go to the sofa's back, the nearest +y cluster within a voxel (which it did before
    own_side). A record on the sofa's back goes there."""
    wall = _plane(1, 30, (0, 0), (40, 27), sign=-1.0)
    sofa = _plane(1, 29, (10, 0), (30, 8), sign=1.0)
    sofa[1][:] = (0.0, 0.94, 0.34)
    floor = _plane(2, 0, (0, 0), (40, 30))
    cells, normals, areas = _scene(wall, sofa, floor)
    c = cl.make_clusters(cells, normals, areas, FINE, budget=64)
    outside = np.c_[np.full(4, 0.35), np.full(4, 3.03), np.full(4, 2.0)]  # in the wall's voxels, facing +y
    on_sofa = np.c_[np.full(4, 0.35), np.full(4, 2.95), np.full(4, 2.0)]
    up = np.tile((0, 1.0, 0), (4, 1))
    flux, escaped = cl.bin_flux(c, _records(outside, up, np.ones((4, 3))), cells, normals)
    assert flux.sum() == 0 and escaped == pytest.approx(12.0)
    flux, escaped = cl.bin_flux(c, _records(on_sofa, sofa[1][:4], np.ones((4, 3))), cells, normals)
    assert escaped == 0 and flux.sum() == pytest.approx(12.0)
    assert (c.records["normal"][flux[:, 0] > 0, 1] > 0.9).all()  # the sofa's back


def _reflect(clusters, weight, irradiance):
    """The flux the voxel sides reflect, per cluster (C, 3): Σ albedo × area × E over each cluster's sides.
    `weight` (R, 3) = albedo × area; `irradiance` (2, R, 3) per side."""
    out = np.zeros((clusters.count, 3))
    for side in range(2):
        members = clusters.side_cluster[:, side]
        use = members >= 0
        for i in range(3):
            out[:, i] += np.bincount(members[use], weight[use, i] * irradiance[side, use, i], clusters.count)
    return out


def test_the_factored_series_equals_the_bounce_by_bounce_series():
    """solve() sums Φ_1 … Φ_N through M_ρ (cluster to cluster) and applies T once; the definition applies T every
    bounce and reflects per receiver side: E_k = T·Φ_k, Φ_(k+1) = reflect(E_k). Random T, albedo and sources;
    equal to float32 rounding (1e-5)."""
    rng = np.random.default_rng(7)
    cells, normals, areas = _scene(_plane(2, 0, (0, 0), (40, 40)), _plane(0, 0, (0, 1), (40, 40)),
                                   _plane(1, 39, (0, 1), (40, 40), sign=-1.0))
    c = cl.make_clusters(cells, normals, areas, FINE, budget=48)
    r = len(cells)
    matrix = rng.uniform(0, 2e-3, (2, c.count, r)).astype(np.float32)
    t = tr.sort_by_cluster(c, matrix)
    weight = rng.uniform(0.2, 0.9, (r, 3)) * areas[:, None]
    first = rng.uniform(0, 5, (c.count, 3))
    m = tr.albedo_transfer(t, weight)
    total, passes = tr.solve(t, m, first, bounces=5, epsilon=0.0)

    expected = np.zeros_like(total, np.float64)
    phi = first
    for k in range(5):
        e = np.stack([(matrix[s].T @ phi) for s in range(2)])
        expected += e
        phi = _reflect(c, weight, e)
    assert len(passes) == 5
    assert np.abs(total - expected).max() <= 1e-5 * np.abs(expected).max()


def test_the_transport_is_capped_only_where_its_reflection_is_impossible():
    """bounded_transport leaves an operator whose clusters deliver under one watt per watt alone (no gain: its
    spectral radius is below the albedo). Where most clusters deliver 1.6 W per watt (what 2 cm walls gave:
    thin_walls' median), the radius exceeds the albedo — every bounce would grow — and exactly the clusters above one
    watt are scaled to one (the rest keep gain 1), folded into M_ρ's columns; then the radius is within the albedo."""
    rng = np.random.default_rng(3)
    cells, normals, areas = _scene(_plane(2, 0, (0, 0), (40, 40)), _plane(0, 0, (0, 1), (40, 40)))
    c = cl.make_clusters(cells, normals, areas, FINE, budget=48)
    centres = (cells + 0.5) * FINE.cell
    gv = SimpleNamespace(cells=cells, axis=np.zeros(len(cells), np.int64), surface_normal=normals, surface_area=areas,
                         positions=centres, bounds=(centres - 0.5 * FINE.cell, centres + 0.5 * FINE.cell), crossings=None)
    weight = 0.8 * areas[:, None] * np.ones(3)
    # Light only on receiver sides that belong to a cluster (the others reflect nothing into M_ρ).
    raw = rng.uniform(0.5, 1.0, (2, c.count, len(cells))) * (c.side_cluster >= 0).T[:, None, :]
    per_watt = sum(raw[s] @ areas for s in range(2))
    for target, expect_gain in ((0.9, False), (1.6, True)):
        want = np.full(c.count, target)
        want[0] = 0.5  # one cluster under a watt in both cases
        matrix = (raw * (want / per_watt)[None, :, None]).astype(np.float32)
        t = tr.sort_by_cluster(c, matrix, gv)
        m = tr.albedo_transfer(t, weight)
        bounded, gain = tr.bounded_transport(t, m, weight)
        if not expect_gain:
            assert gain is None and bounded is m
            continue
        np.testing.assert_allclose(gain, np.where(want > 1, 1 / want, 1.0), rtol=1e-5)
        np.testing.assert_allclose(bounded, m * gain[None, None, :], rtol=1e-6)
        assert max(np.abs(np.linalg.eigvals(bounded[ch])).max() for ch in range(3)) <= 0.8 * (1 + 1e-6)


def test_the_radius_test_decides_as_the_eigenvalues_do():
    """radius_at_most against numpy's eigenvalues on random non-negative matrices (dense, sparse, with rows and
    columns of zeros, as clusters that receive or send nothing): right for bounds 2% either side of the radius. Each
    has some light that a cluster sends back to itself (a positive diagonal, as a folded cluster's), so power
    iteration converges: on a periodic matrix (two clusters that see only each other) it oscillates, and the
    undecided fallback, a power iteration's estimate, can be wrong."""
    rng = np.random.default_rng(11)
    for k in range(200):
        n = int(rng.integers(2, 60))
        m = rng.random((n, n)) * (rng.random((n, n)) < rng.uniform(0.05, 1.0)) + np.diag(0.1 * rng.random(n))
        m[rng.random(n) < 0.1] = 0.0
        m[:, rng.random(n) < 0.1] = 0.0
        r = float(np.abs(np.linalg.eigvals(m)).max())
        if r == 0.0:
            continue
        assert tr.radius_at_most(m, 1.02 * r) and not tr.radius_at_most(m, 0.98 * r), k
    assert tr.radius_at_most(np.zeros((0, 0)), 0.5)  # no clusters (an empty scene)


@pytest.mark.parametrize("runs", [True, False])
def test_take_columns_is_a_column_gather(runs):
    """transfer_update.take_columns (a gather a row at a time): the same as np.take for runs of consecutive columns
    (an update's kept receivers) and for scattered ones, and with rows (the kept clusters' old rows, one repeated
    for a fresh cluster) the same as taking the rows first."""
    from bounce_gi.gpu_kernels.lpv.transfer_update import take_columns
    rng = np.random.default_rng(3)
    src = rng.random((7, 500)).astype(np.float32)
    if runs:  # blocks of consecutive columns, shuffled, one column repeated (a fresh receiver's placeholder)
        blocks = [np.arange(a, a + n) for a, n in ((300, 40), (0, 120), (120, 5), (200, 90), (0, 1), (450, 50))]
        columns = np.concatenate([blocks[i] for i in rng.permutation(len(blocks))])
    else:
        columns = rng.integers(0, 500, 300)
    out = np.empty((7, len(columns)), np.float32)
    take_columns(src, columns, out)
    assert np.array_equal(out, np.take(src, columns, axis=1))
    rows = np.array([3, 0, 0, 6, 2, 5, 1, 4])
    out = np.empty((len(rows), len(columns)), np.float32)
    take_columns(src, columns, out, rows=rows)
    assert np.array_equal(out, np.take(np.take(src, rows, axis=0), columns, axis=1))


def test_source_chunks_cover_every_source_once_within_the_budget():
    """transfer_update.source_chunks: consecutive ranges, each at most `most` pairs unless one source alone has
    more, together every source with pairs."""
    from bounce_gi.gpu_kernels.lpv.transfer_update import source_chunks
    counts = np.array([3, 0, 4, 2, 9, 1, 1, 0, 0])
    chunks = source_chunks(counts, 5)
    assert chunks == [(0, 2), (2, 3), (3, 4), (4, 5), (5, 9)]
    assert all(counts[a:b].sum() <= 5 or b - a == 1 for a, b in chunks)
    assert source_chunks(np.zeros(4, int), 5) == []


def test_a_detached_bit_in_a_walls_block_and_plane_leaves_the_walls_cluster_where_the_wall_is():
    """A wall (8 × 8 voxels) and, in its block and plane but three voxels above its top, a bit of something else (2
    voxels: at a town block's scale, a tree's crown beside a façade). Too small to be a cluster of its own, the bit
    joins the wall's cluster (its flux and area count there), but the cluster's record and the octagon its kernel
    integrates near it are the wall's (_group's core): with the bit, the octagon spanned the gap to it and the wall's
    light was spread over both (here to z = 1.3, the centroid at z = 0.424) — at a town block's scale a façade's
    octagon 24 m wide for its 6 m, 0.7 m in front of it."""
    wall = _plane(1, 10, (0, 0), (8, 8))  # y index 10: z 0–8, x 0–8
    bit = _plane(1, 10, (11, 0), (13, 1))  # z 11–13, x 0–1
    floor = _plane(2, 0, (0, 0), (16, 20))
    cells, normals, areas = _scene(wall, bit, floor)
    c = cl.make_clusters(cells, normals, areas, FINE, 0, block=16)
    j = c.side_cluster[0, 0]  # the wall's first voxel, front (+y) side
    assert (c.side_cluster[len(wall[0]):len(wall[0]) + 2, 0] == j).all()  # the bit is in the wall's cluster
    assert c.records["normal"][j, 3] == pytest.approx(0.66)  # with its area
    assert c.records["position"][j, [0, 2]] == pytest.approx((0.4, 0.4))  # the wall's centroid
    assert c.polygon[j, :, 2].max() == pytest.approx(0.8, abs=1e-6)  # the wall's top


@pytest.mark.parametrize("voxels, clusters", [(6_000, 1024), (16_000, 750), (30_000, 512), (2_000_000, 0)])
def test_a_scene_of_few_surface_voxels_gets_finer_clusters_for_a_large_rooms_pairs(monkeypatch, voxels, clusters):
    """The cached transport's clusters (lpv/passes.transfer_budget): gather_vpls (512), up to twice as many while
    clusters × surface voxels stay within transfer_pairs (12 M: a large room's 512 × 23 000), and none where T would
    not fit transfer_mb (512 MiB; it gathers then). An outdoor block at 32³ (6 700 surface voxels) gets 1024: its
    Diffuse Indirect 0.200 -> 0.128 against Cycles (tests/accuracy/test_examples_vs_cycles.py)."""
    from bounce_gi.gpu_kernels.lpv import passes
    from bounce_gi.gpu_kernels.lpv.settings import LpvSettings

    monkeypatch.setattr(passes, "surface_voxels", lambda scene, grids: float(voxels))
    assert passes.transfer_budget(None, [FINE], LpvSettings()) == clusters
    assert passes.transfer_budget(None, [FINE], LpvSettings(transfer_pairs=0)) == (512 if clusters else 0)


def test_a_detached_piece_outside_the_walls_box_keeps_its_own_cluster_where_the_budget_allows():
    """The wall and the bit above it, clustered to a budget (no block given). Where the clusters fit with it, the
    bit is a cluster of its own, its record where it is (a strip of ground in front of a façade, cut off by the
    façade from the ground under the building: joined to that, its light left metres away — an unseen building on a
    ground plane, Diffuse Indirect 0.166 -> 0.133); where they would not (budget 6 here), it joins the wall's as
    before. An update after an edit keeps the choice (Clusters.detached) with the block."""
    cells, normals, areas = _scene(_plane(1, 10, (0, 0), (8, 8)), _plane(1, 10, (11, 0), (13, 1)),
                                   _plane(2, 0, (0, 0), (16, 20)))
    own = cl.make_clusters(cells, normals, areas, FINE, 8)
    wall, bit = own.side_cluster[0, 0], own.side_cluster[64, 0]
    assert own.detached and own.count <= 8 and wall != bit
    assert own.records["position"][bit, 2] == pytest.approx(1.2)
    assert own.records["normal"][bit, 3] == pytest.approx(0.02)
    joined = cl.make_clusters(cells, normals, areas, FINE, 6)
    assert not joined.detached and joined.side_cluster[0, 0] == joined.side_cluster[64, 0]
    again = cl.make_clusters(cells, normals, areas, FINE, 0, block=own.block, detached=own.detached)
    assert np.array_equal(again.side_cluster, own.side_cluster)
