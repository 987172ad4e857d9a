# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's cached transport (LpvSettings.transport = "transfer", the default): the gathered transport of
lpv/gather.py with its geometry-dependent part kept across light, material and world edits (the world is a light:
common/lights.py's sky light, whose RSMs give its first bounce like any other light's).

For fixed geometry the gather is linear in the light that enters it. Its receivers are the surface voxels' surfaces
per dominant axis, where they lie (lpv/receivers.py), and its sources their sides grouped, once per geometry, into
clusters (lpv/clusters.py). The kernel of lpv/gather.glsl (cosines, distance, disc limit or the cluster's rectangle,
visibility through the cells' planes: everything but the flux) is evaluated once per receiver and cluster on the GPU
(MODE_TRANSFER) and read back: the transfer T_s (C × R, per side s). Then an edit of the lights or the world costs
only:

    Φ_1        the RSM's VPL flux binned into the clusters (flux kept exactly)
    Φ_(k+1)    = M_ρ Φ_k                                              (C × C per channel: microseconds)
    E_total    = T · (Φ_1 + Φ_2 + … + Φ_N)                            (one product with T)

where reflect(E) sums albedo × area × E over each cluster's voxel sides, and M_ρ = reflect ∘ T, the cluster-to-
cluster transfer with the receivers' albedo (re-built on a material edit, which re-voxelises only the albedo:
occupancy and T are kept). A geometry edit updates T (update_transfer) instead of rebuilding it. This is the
precomputed-radiosity factorisation of Enlighten-style systems (Martin and Einarsson, "A real-time radiosity
architecture for video games", SIGGRAPH 2010 course), evaluated live. Every bounce is computed (no tail
extrapolation); the series stops once a bounce adds less than `epsilon` of the largest pass's flux.

Memory: T holds 2 × C × R float32 (R receivers); C shrinks to fit `transfer_mb`, and below MIN_CLUSTERS (or with
cascades) the transport falls back to the per-bounce gather (lpv/gather.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from ..gl.bind import bind_grid, dispatch, set_uniform
from .clusters import Clusters
from .crossings import bind_visibility
from .gather import vpls_per_dispatch

MIN_CLUSTERS = 64  # fewer sources than this blur a room's bounce into a few blobs: gather instead
ROWS_BYTES = 8 << 20  # GPU buffer T is read back through, a dispatch at a time


def build_transfer(ctx, programs, gv, grid: Grid, clusters: Clusters, occlusion: bool, update=None) -> np.ndarray:
    """T: (2, C, R) float32 — what cluster c of unit flux gives receiver r's front (0) and back (1) side, the kernel
    of lpv/gather.glsl evaluated on the GPU (MODE_TRANSFER), in dispatches of at most vpls_per_dispatch sources
    and ROWS_BYTES. With `update` = (fresh receivers (R,) bool, fresh clusters (C,) bool, box (2, 3)), only pairs with
    a fresh end or a ray through the box are evaluated; the rest come back NaN (update_transfer fills them)."""
    r, c = int(gv.surface_count), clusters.count
    out = np.zeros((2, c, r), np.float32)
    if r == 0 or c == 0:
        return out
    prog = programs.compute("lpv/gather.glsl", {"MODE_TRANSFER": 1})
    bind_visibility(prog, gv)
    gv.receivers.bind_to_storage_buffer(10)
    set_uniform(prog, "u_occlusion", bool(occlusion))
    set_uniform(prog, "u_fine_origin", tuple(float(v) for v in gv.fine.origin))
    set_uniform(prog, "u_surface_count", r)
    bind_grid(prog, grid)
    records, receivers = clusters.records.copy(), None
    set_uniform(prog, "u_update", update is not None)
    if update is not None:
        fresh_receivers, fresh_clusters, box = update
        records["flux"][:, 3] = fresh_clusters
        cells = np.zeros((r, 4), np.int32)
        cells[:, :3], cells[:, 3] = gv.cells, fresh_receivers
        receivers = ctx.buffer(cells.tobytes())
        set_uniform(prog, "u_box_lo", tuple(float(v) for v in box[0]))
        set_uniform(prog, "u_box_hi", tuple(float(v) for v in box[1]))
    sources = ctx.buffer(records.tobytes())
    sources.bind_to_storage_buffer(6)
    polygons = ctx.buffer(np.ascontiguousarray(clusters.polygon, np.float32).tobytes())
    polygons.bind_to_storage_buffer(9)
    (receivers or gv.surfaces).bind_to_storage_buffer(7)
    chunk = max(1, min(vpls_per_dispatch(grid), ROWS_BYTES // (8 * r)))
    rows = ctx.buffer(reserve=min(chunk, c) * r * 8)
    rows.bind_to_storage_buffer(8)
    for first in range(0, c, chunk):
        count = min(chunk, c - first)
        set_uniform(prog, "u_vpl_first", first)
        set_uniform(prog, "u_vpl_count", count)
        dispatch(prog, (r,), local=64)
        ctx.memory_barrier()
        block = np.frombuffer(rows.read(size=count * r * 8), np.float32).reshape(count, r, 2)
        out[0, first:first + count] = block[..., 0]
        out[1, first:first + count] = block[..., 1]
    for buffer in (rows, sources, polygons, receivers):
        if buffer is not None:
            buffer.release()
    return out


def _match(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """For each row of `new` (structured or 2-D), the index of an identical row of `old`, or −1."""
    old_keys = {row.tobytes(): i for i, row in enumerate(old)}
    return np.array([old_keys.get(row.tobytes(), -1) for row in new], np.int64)


def _receivers(cells, axis, normals, areas) -> np.ndarray:
    """(R, 8) rows a receiver is compared by: its fine voxel, axis, normal and area."""
    return np.concatenate([cells.astype(np.float64), axis[:, None], normals, areas[:, None]], axis=1)


def _match_receivers(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """_match for _receivers rows, vectorised: a receiver is one (voxel, axis), so rows are paired by that key
    (sorted search) and then kept only where the whole row (normal, area) is equal."""
    def key(rows):
        c = rows[:, :4].astype(np.int64)
        return ((c[:, 2] * (1 << 20) + c[:, 1]) * (1 << 20) + c[:, 0]) * 4 + c[:, 3]
    old_key, new_key = key(old), key(new)
    order = np.argsort(old_key, kind="stable")
    at = np.minimum(np.searchsorted(old_key[order], new_key), max(len(old) - 1, 0))
    if len(old) == 0:
        return np.full(len(new), -1, np.int64)
    index = order[at]
    same = (old_key[index] == new_key) & (old[index] == new).all(axis=1)
    return np.where(same, index, -1)


def changed_box(moved: np.ndarray, grid: Grid):
    """The box (2, 3) of the LPV cells holding the fine voxels `moved` (voxels that appeared, vanished, or got
    another normal or area): a cell's visibility planes come from its eight voxels (lpv/crossings.py; LPV cell c
    holds fine voxels 2c + 1 and 2c + 2 along each axis). None when none did."""
    if len(moved) == 0:
        return None
    cells = np.floor((np.asarray(moved) - 1) / 2)
    origin = np.asarray(grid.origin)
    return np.stack([origin + cells.min(axis=0) * grid.cell, origin + (cells.max(axis=0) + 1) * grid.cell])


def update_transfer(ctx, programs, gv, grid: Grid, occlusion: bool, prior) -> tuple:
    """T after a geometry edit, from `prior` (the Transfer before it): the clusters re-made with the same blocks,
    and only the pairs the edit can change re-evaluated — a new receiver or source, or a ray through the changed
    box. Returns (clusters, matrix, the share of pairs re-evaluated)."""
    from .clusters import make_clusters

    new = make_clusters(gv.cells, gv.surface_normal, gv.surface_area, gv.fine, 0, block=prior.clusters.block,
                        positions=gv.positions, bounds=gv.bounds)
    before = _receivers(prior.cells, prior.axis, prior.normals, prior.areas)
    after = _receivers(gv.cells, gv.axis, gv.surface_normal, gv.surface_area)
    old_r = _match_receivers(before, after)
    old_c = _match(prior.clusters.records, new.records)
    gone = _match_receivers(after, before) < 0
    box = changed_box(np.concatenate([before[gone, :3], after[old_r < 0, :3]]), grid)
    if box is None:
        box = np.zeros((2, 3))
    matrix = build_transfer(ctx, programs, gv, grid, new, occlusion, (old_r < 0, old_c < 0, box))
    kept = 0
    for side in range(2):  # the kept pairs' old values: prior's columns are sorted by cluster, undo that
        keep = np.isnan(matrix[side])
        kept += int(np.count_nonzero(keep))
        position = np.empty(len(prior.order[side]), np.int64)
        position[prior.order[side]] = np.arange(len(position))
        # np.take, not fancy indexing: several times faster on a matrix this size (numpy gathers columns row by row)
        rows = np.take(prior.matrix[side], np.maximum(old_c, 0), axis=0)
        np.copyto(matrix[side], np.take(rows, position[np.maximum(old_r, 0)], axis=1), where=keep)
    return new, matrix, 1.0 - kept / max(matrix.size, 1)


@dataclass
class Transfer:
    """One cascade's cached transport: its clusters and T, each side's columns in the order of that side's
    clusters (`order[s]`: receiver of each column; the receivers whose side has no cluster last), so that a
    cluster's receivers are one contiguous slice (`starts[s]`) for albedo_transfer; and the receivers it was made
    for (update_transfer compares them with the next geometry's)."""
    clusters: Clusters
    matrix: np.ndarray  # (2, C, R) float32
    order: list  # per side: (R,) receiver index of each column
    starts: list  # per side: (C + 1,) first column of each cluster; columns past starts[s][-1] have none
    grid: Grid = None
    cells: np.ndarray = None  # (R, 3) the receivers' fine voxels, axes (lpv/receivers.py), normals and areas
    axis: np.ndarray = None
    normals: np.ndarray = None
    areas: np.ndarray = None
    updated: float = 1.0  # the share of T evaluated when it was made (1: all of it; less after an edit)

    @property
    def nbytes(self) -> int:
        return self.matrix.nbytes


def sort_by_cluster(clusters: Clusters, matrix: np.ndarray, gv=None, grid: Grid | None = None,
                    updated: float = 1.0) -> Transfer:
    """`matrix` (2, C, R) in receiver order → a Transfer with each side's columns grouped by cluster (and the
    receivers of `gv` recorded)."""
    order, starts, out = [], [], np.empty_like(matrix)
    for side in range(2):
        members = clusters.side_cluster[:, side]
        key = np.where(members >= 0, members, clusters.count)
        perm = np.argsort(key, kind="stable")
        np.take(matrix[side], perm, axis=1, out=out[side])  # 5× faster than matrix[side][:, perm] here
        order.append(perm)
        starts.append(np.searchsorted(key[perm], np.arange(clusters.count + 1)))
    if gv is None:
        return Transfer(clusters, out, order, starts, updated=updated)
    return Transfer(clusters, out, order, starts, grid, gv.cells.copy(), gv.axis.copy(), gv.surface_normal.copy(),
                    gv.surface_area.copy(), updated)


def spectral_radius(m: np.ndarray, iterations: int = 100) -> float:
    """The largest |eigenvalue| of a non-negative square matrix, by power iteration from the all-ones vector."""
    v = np.ones(m.shape[1])
    r = 0.0
    for _ in range(iterations):
        w = m @ v
        norm = float(np.linalg.norm(w))
        if norm == 0.0:
            return 0.0
        r, v = norm / float(np.linalg.norm(v)), w / norm
    return r


def bounded_transport(t: Transfer, m_rho: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(M_ρ, gain): M_ρ as it is and no gain where the reflection can be physical, else every cluster's flux capped
    so that it delivers at most one watt per watt (gain (C,) ≤ 1, folded into M_ρ's columns; solve applies it to T).

    The exact operator has spectral radius r ≤ ρ_max, the brightest receiver's albedo: a cluster's watt lands at
    most once, and a receiver reflects at most ρ_max of it. The voxel kernel breaks that where a slab thinner than
    a voxel puts its two faces' voxels within END_CELLS of each other (lpv/gather.glsl: the crossing at a receiver's
    own end is not counted): the back side of the far face's voxel, inside the slab, receives the light its near
    face did and reflects it again. Behind 2 cm walls clusters delivered up to 2.5 W per watt, r reached 1.5 ρ_max,
    and every bounce grew. In the other example rooms r stays below ρ_max (0.67–0.99 of it) although single clusters
    scatter around one watt (0.8 to 1.4): capping those would darken them (furnished's Combined 0.10 → 0.14), so
    the cap applies only where r shows the operator is impossible."""
    areas = np.asarray(t.areas, np.float64)
    per_area = side_weights(weight) / np.maximum(areas[None, :, None], 1e-30)
    rho = per_area.reshape(-1, per_area.shape[-1]).max(axis=0, initial=0.0)
    if all(spectral_radius(m_rho[ch]) <= rho[ch] for ch in range(m_rho.shape[0])):
        return m_rho, None
    delivered = sum(t.matrix[side].astype(np.float64) @ areas[t.order[side]]
                    for side in range(2))
    gain = np.where(delivered > 1.0, 1.0 / np.maximum(delivered, 1e-30), 1.0)
    return m_rho * gain[None, None, :], gain


def side_weights(weight: np.ndarray) -> np.ndarray:
    """albedo × area per receiver side, (2, R, 3) float64, from (2, R, 3) or one (R, 3) for both sides."""
    w = np.asarray(weight, np.float64)
    return np.broadcast_to(w, (2,) + w.shape) if w.ndim == 2 else w


def albedo_transfer(t: Transfer, weight: np.ndarray) -> np.ndarray:
    """M_ρ (3, C, C): M[ch, c', c] = the flux cluster c' reflects in channel ch when cluster c emits one watt —
    Σ over c'’s voxel sides of albedo × area × T (`weight`: side_weights), one small product per cluster and side
    over its contiguous columns (all three channels at once: T is read once)."""
    count = t.clusters.count
    weight = side_weights(weight)
    out = np.zeros((count, count, 3), np.float32)  # [c', c, ch]
    for side in range(2):
        w = weight[side][t.order[side]].astype(np.float32)
        starts = t.starts[side]
        for c in range(count):
            a, b = starts[c], starts[c + 1]
            if b > a:
                out[c] += t.matrix[side][:, a:b] @ w[a:b]
    return np.ascontiguousarray(out.transpose(2, 0, 1), np.float64)


def solve(t: Transfer, m_rho: np.ndarray, first: np.ndarray, bounces: int, epsilon: float,
          gain: np.ndarray | None = None) -> tuple[np.ndarray, list]:
    """Irradiance summed over `bounces` passes, (2, R, 3) per side: T × the sources' flux summed over passes —
    `first` (C, 3) from the RSM, each further pass's the reflection of the one before (M_ρ), each cluster's flux
    times `gain` where T carries it (bounded_transport; M_ρ has it folded in). Stops once a pass's flux is below
    `epsilon` of the largest so far. Returns the totals and, per pass, its source flux."""
    phi = np.asarray(first, np.float64)
    total = phi.copy()
    passes = [float(phi.sum())]
    following = np.einsum("kij,jk->ik", m_rho, phi)
    for _ in range(2, bounces + 1):
        phi = following
        passes.append(float(phi.sum()))
        total += phi
        if passes[-1] <= epsilon * max(passes):
            break
        following = np.einsum("kij,jk->ik", m_rho, phi)
    sums = (total if gain is None else total * gain[:, None]).T.astype(np.float32)  # (3, C)
    out = np.empty((2, t.matrix.shape[2], 3), np.float32)
    for side in range(2):
        out[side, t.order[side]] = (sums @ t.matrix[side]).T
    return out, passes
