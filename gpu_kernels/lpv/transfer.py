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
occupancy and T are kept). A geometry edit updates T (lpv/transfer_update.py) instead of rebuilding it. This is
the precomputed-radiosity factorisation of Enlighten-style systems (Martin and Einarsson, "A real-time radiosity
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
from ..gl.host_threads import beside
from .clusters import Clusters
from .crossings import bind_visibility
from .gather import vpls_per_dispatch

MIN_CLUSTERS = 64  # fewer sources than this blur a room's bounce into a few blobs: gather instead
ROWS_BYTES = 8 << 20  # GPU buffer T is read back through, a dispatch at a time


def kernel_program(ctx, programs, gv, grid: Grid, clusters: Clusters, occlusion: bool, defines=None) -> tuple:
    """lpv/gather.glsl's MODE_TRANSFER program with the geometry volume, its receivers and `clusters`' records and
    polygons bound: (program, the buffers made for it, to release)."""
    prog = programs.compute("lpv/gather.glsl", {"MODE_TRANSFER": 1, **(defines or {})})
    bind_visibility(prog, gv)
    gv.receivers.bind_to_storage_buffer(10)
    set_uniform(prog, "u_occlusion", bool(occlusion))
    set_uniform(prog, "u_surface_count", int(gv.surface_count))
    bind_grid(prog, grid)
    sources = ctx.buffer(clusters.records.tobytes())
    sources.bind_to_storage_buffer(6)
    polygons = ctx.buffer(np.ascontiguousarray(clusters.polygon, np.float32).tobytes())
    polygons.bind_to_storage_buffer(9)
    return prog, [sources, polygons]


def build_transfer(ctx, programs, gv, grid: Grid, clusters: Clusters, occlusion: bool) -> np.ndarray:
    """T: (2, C, R) float32 — what cluster c of unit flux gives receiver r's front (0) and back (1) side, the kernel
    of lpv/gather.glsl evaluated on the GPU (MODE_TRANSFER), in dispatches of at most vpls_per_dispatch sources
    and ROWS_BYTES."""
    r, c = int(gv.surface_count), clusters.count
    out = np.zeros((2, c, r), np.float32)
    if r == 0 or c == 0:
        return out
    prog, buffers = kernel_program(ctx, programs, gv, grid, clusters, occlusion)
    chunk = max(1, min(vpls_per_dispatch(grid), ROWS_BYTES // (8 * r)))
    for first, count, data in dispatch_in_runs(ctx, prog, c, chunk, r, 8 * r):
        block = np.frombuffer(data, np.float32).reshape(count, r, 2)
        out[0, first:first + count] = block[..., 0]
        out[1, first:first + count] = block[..., 1]
    for buffer in buffers:
        buffer.release()
    return out


def dispatch_in_runs(ctx, prog, total: int, run: int, invocations: int, item_bytes: int, names=("u_vpl_first",
                     "u_vpl_count")):
    """Yield (first, count, bytes) for each run of at most `run` of `total` items: `prog` dispatched over
    `invocations` (groups of 64; 0: one per item of the run) with the run's first item and count in the uniforms
    `names`, and what it wrote to storage buffer 8 (count × `item_bytes`, a buffer made for the loop) read back."""
    out = ctx.buffer(reserve=max(1, min(run, total)) * item_bytes)
    out.bind_to_storage_buffer(8)
    try:
        for first in range(0, total, run):
            count = min(run, total - first)
            set_uniform(prog, names[0], first)
            set_uniform(prog, names[1], count)
            dispatch(prog, (invocations if invocations else count,), local=64)
            ctx.memory_barrier()
            yield first, count, out.read(size=count * item_bytes)
    finally:
        out.release()


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
    rows: np.ndarray = None  # receiver_rows: what the next geometry's receivers are compared with
    crossings: dict = None  # the visibility planes T was made with (lpv/crossings.py), likewise

    @property
    def nbytes(self) -> int:
        return self.matrix.nbytes


def cluster_order(clusters: Clusters) -> tuple[list, list]:
    """Per side: the receivers in the order of their side's clusters (stable: by receiver within one), and each
    cluster's first column in that order (C + 1; the receivers whose side has no cluster last)."""
    order, starts = [], []
    for side in range(2):
        members = clusters.side_cluster[:, side]
        key = np.where(members >= 0, members, clusters.count)
        perm = np.argsort(key, kind="stable")
        order.append(perm)
        starts.append(np.searchsorted(key[perm], np.arange(clusters.count + 1)))
    return order, starts


def empty_matrix(shape: tuple, spare: np.ndarray | None = None, most: int | None = None) -> np.ndarray:
    """An uninitialised float32 array of `shape`, in the memory of `spare` (a T no longer kept: PassCache.spare)
    where that holds it and is at most a quarter larger (a small T would otherwise keep a large one's memory), else
    in new memory with up to an eighth to spare (no more than `most` elements in all: the transfer_mb budget), so
    that the next edit's T, a few clusters or receivers larger, fits in it. New memory costs its page faults when
    first written (the kernel's, zeroing and finding huge pages: up to 0.1 s for the Cornell box's 90 MB), memory
    reused does not."""
    n = int(np.prod(shape))
    flat = _buffer(spare)
    if flat is not None and n <= flat.size <= n + n // 4:
        return flat[:n].reshape(shape)
    room = n // 8 if most is None else max(0, min(n // 8, int(most) - n))
    return np.empty(n + room, np.float32)[:n].reshape(shape)


def _buffer(a: np.ndarray | None) -> np.ndarray | None:
    """The whole float32 buffer `a` is a view of (empty_matrix's, with its spare room), flat; None if there is none."""
    while a is not None and isinstance(a.base, np.ndarray):
        a = a.base
    usable = a is not None and a.dtype == np.float32 and a.flags.c_contiguous and a.flags.writeable
    return a.reshape(-1) if usable else None


def sort_by_cluster(clusters: Clusters, matrix: np.ndarray, gv=None, grid: Grid | None = None,
                    spare: np.ndarray | None = None, most: int | None = None) -> Transfer:
    """`matrix` (2, C, R) in receiver order → a Transfer with each side's columns grouped by cluster (and the
    receivers of `gv` recorded), written into `spare`'s memory where it fits (empty_matrix; `most`: its cap)."""
    order, starts = cluster_order(clusters)
    out = empty_matrix(matrix.shape, spare, most)
    for side in range(2):
        np.take(matrix[side], order[side], axis=1, out=out[side])  # 5× faster than matrix[side][:, perm] here
    return sorted_transfer(clusters, out, order, starts, gv, grid)


def sorted_transfer(clusters: Clusters, matrix: np.ndarray, order: list, starts: list, gv=None,
                    grid: Grid | None = None, updated: float = 1.0, rows: np.ndarray | None = None) -> Transfer:
    """A Transfer of `matrix` whose columns are already in cluster_order's `order` (`rows`: receiver_rows(gv),
    where the caller has them)."""
    if gv is None:
        return Transfer(clusters, matrix, order, starts, updated=updated)
    return Transfer(clusters, matrix, order, starts, grid, gv.cells.copy(), gv.axis.copy(), gv.surface_normal.copy(),
                    gv.surface_area.copy(), updated, receiver_rows(gv) if rows is None else rows, gv.crossings)


def receiver_rows(gv) -> np.ndarray:
    """(R, 17) float64 per receiver: its fine voxel, axis, normal, area, where its surfaces lie and the box they span
    — what the kernel and the visibility planes read of it, so a receiver whose row is unchanged after an edit keeps
    its pairs (lpv/transfer_update.py). A surface moved within its voxel keeps the first four, not the rest."""
    lo, hi = gv.bounds
    return np.concatenate([gv.cells.astype(np.float64), gv.axis[:, None], gv.surface_normal,
                           gv.surface_area[:, None], gv.positions, lo, hi], axis=1)


def radius_at_most(m: np.ndarray, bound: float, iterations: int = 100) -> bool:
    """Whether the spectral radius r of a non-negative square matrix is at most `bound`. For any positive v,
    min_i (Mv)_i / v_i ≤ r ≤ max_i (Mv)_i / v_i (the Collatz–Wielandt bounds), so power iteration from the
    all-ones vector, kept positive, stops as soon as they decide — a few products on the example scenes, where r is
    0.70–0.95 of the bound: 0.1–1 ms a channel against 3–20 ms for the 100 power iterations that estimated r
    before, which a geometry or material edit paid. Undecided after `iterations`: the power iteration's estimate
    decides."""
    if m.size == 0:  # no clusters: nothing reflects
        return 0.0 <= bound
    v = np.ones(m.shape[1])
    r = 0.0
    for _ in range(iterations):
        w = m @ v
        ratio = w / v
        if ratio.max() <= bound:
            return True
        if ratio.min() > bound:
            return False
        norm = float(np.linalg.norm(w))
        r, v = norm / float(np.linalg.norm(v)), w / norm
        v = np.maximum(v, 1e-12)  # positive, so that the bounds hold (a row of zeros would zero its entry)
    return r <= bound


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
    if all(radius_at_most(m_rho[ch], rho[ch]) for ch in range(m_rho.shape[0])):
        return m_rho, None
    # float32 products (BLAS on T as it is): a float64 copy of T cost 60 ms at 500 clusters × 20 000 receivers, for
    # a cap that float32's sums set to 1e-6
    delivered = sum(t.matrix[side] @ areas[t.order[side]].astype(np.float32) for side in range(2)).astype(np.float64)
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


def _reflect(m_rho: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """The sources' flux after one more reflection, (C, 3): M_ρ (3, C, C) per colour channel times φ (C, 3), in
    M_ρ's precision. One batched matrix-vector product (BLAS), where einsum's loop took four times as long at 1024
    clusters."""
    return np.matmul(m_rho, phi.T.astype(m_rho.dtype)[:, :, None])[..., 0].T


def solve(t: Transfer, m_rho: np.ndarray, first: np.ndarray, bounces: int, epsilon: float,
          gain: np.ndarray | None = None) -> tuple[np.ndarray, list]:
    """Irradiance summed over `bounces` passes, (2, R, 3) per side: T × the sources' flux summed over passes —
    `first` (C, 3) from the RSM, each further pass's the reflection of the one before (M_ρ), each cluster's flux
    times `gain` where T carries it (bounded_transport; M_ρ has it folded in). Stops once a pass's flux is below
    `epsilon` of the largest so far. Returns the totals and, per pass, its source flux."""
    phi = np.asarray(first, np.float64)
    total = phi.copy()
    passes = [float(phi.sum())]
    following = _reflect(m_rho, phi)
    for _ in range(2, bounces + 1):
        phi = following.astype(np.float64)
        passes.append(float(phi.sum()))
        total += phi
        if passes[-1] <= epsilon * max(passes):
            break
        following = _reflect(m_rho, phi)
    sums = (total if gain is None else total * gain[:, None]).T.astype(np.float32)  # (3, C)
    out = np.empty((2, t.matrix.shape[2], 3), np.float32)

    def side_product(side):  # reading T is most of a light edit's solve: one side on each of two cores
        out[side, t.order[side]] = (sums @ t.matrix[side]).T
    back = beside(side_product, 1)
    side_product(0)
    back.result()
    return out, passes
