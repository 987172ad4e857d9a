# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's cached transport (LpvSettings.transport = "transfer", the default): the gathered transport of
lpv/gather.py with its geometry-dependent part kept across light, material and world edits.

For fixed geometry the gather is linear in the light that enters it. Its sources are fixed here: the surface voxels'
sides grouped, once per geometry, into clusters (lpv/clusters.py). The kernel of
lpv/gather.glsl (cosines, distance, disc limit and fuzzy visibility: everything but the flux) is evaluated once per
receiver voxel and cluster on the GPU (MODE_TRANSFER) and read back: the transfer T_s (C × R, per side s). Then an
edit of the lights or the world costs only:

    Φ_1        the RSM's VPL flux binned into the clusters (flux kept exactly)
    E_world    the world light, propagated and absorbed as before (re-run only when the world changes)
    Φ_2        = reflect(E_world) + M_ρ Φ_1,   Φ_(k+1) = M_ρ Φ_k      (C × C per channel: microseconds)
    E_total    = E_world + T · (Φ_1 + Φ_2 + … + Φ_N)                 (one product with T)

where reflect(E) sums albedo × area × E over each cluster's voxel sides, and M_ρ = reflect ∘ T, the cluster-to-
cluster transfer with the receivers' albedo (re-built on a material edit, without re-voxelising). This is the
precomputed-radiosity factorisation of Enlighten-style systems (Martin and Einarsson, "A real-time radiosity
architecture for video games", SIGGRAPH 2010 course), evaluated live. Every bounce is computed (no tail
extrapolation); the series stops once a bounce adds less than `epsilon` of the first reflection's flux.

Memory: T holds 2 × C × R float32 (R surface voxels); C shrinks to fit `transfer_mb`, and below MIN_CLUSTERS the
transport falls back to the per-bounce gather (lpv/gather.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from ..gl.bind import bind_grid, bind_named, dispatch, set_uniform
from .clusters import Clusters
from .gather import vpls_per_dispatch

MIN_CLUSTERS = 64  # fewer sources than this blur a room's bounce into a few blobs: gather instead


def build_transfer(ctx, programs, gv, grid: Grid, clusters: Clusters, occlusion: bool) -> np.ndarray:
    """T: (2, C, R) float32 — what cluster c of unit flux gives receiver r's front (0) and back (1) side, the kernel
    of lpv/gather.glsl evaluated on the GPU (MODE_TRANSFER), in dispatches of at most vpls_per_dispatch sources
    and 64 MiB."""
    r, c = int(gv.surface_count), clusters.count
    out = np.zeros((2, c, r), np.float32)
    if r == 0 or c == 0:
        return out
    prog = programs.compute("lpv/gather.glsl", {"MODE_TRANSFER": 1})
    bind_named(prog, [("u_voxel_normal", gv.normal), ("u_voxel_area", gv.area), ("u_coverage", gv.coverage),
                      ("u_layers", gv.layers)])
    set_uniform(prog, "u_occlusion", bool(occlusion))
    set_uniform(prog, "u_fine_origin", tuple(float(v) for v in gv.fine.origin))
    set_uniform(prog, "u_surface_count", r)
    bind_grid(prog, grid)
    sources = ctx.buffer(clusters.records.tobytes())
    sources.bind_to_storage_buffer(6)
    gv.surfaces.bind_to_storage_buffer(7)
    chunk = max(1, min(vpls_per_dispatch(grid), (64 << 20) // (8 * r)))
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
    rows.release()
    sources.release()
    return out


def reflect(clusters: Clusters, weight: np.ndarray, irradiance: np.ndarray) -> np.ndarray:
    """The flux the voxel sides reflect, per cluster (C, 3): Σ albedo × area × E over each cluster's sides.
    `weight` (R, 3) = albedo × area; `irradiance` (2, R, 3) per side."""
    out = np.zeros((clusters.count, 3))
    for side in range(2):
        members = clusters.side_cluster[:, side]
        use = members >= 0
        for i in range(3):
            out[:, i] += np.bincount(members[use], weight[use, i] * irradiance[side, use, i], clusters.count)
    return out


@dataclass
class Transfer:
    """One cascade's cached transport: its clusters and T, each side's columns in the order of that side's
    clusters (`order[s]`: receiver of each column; the receivers whose side has no cluster last), so that a
    cluster's receivers are one contiguous slice (`starts[s]`) for albedo_transfer."""
    clusters: Clusters
    matrix: np.ndarray  # (2, C, R) float32
    order: list  # per side: (R,) receiver index of each column
    starts: list  # per side: (C + 1,) first column of each cluster; columns past starts[s][-1] have none

    @property
    def nbytes(self) -> int:
        return self.matrix.nbytes


def sort_by_cluster(clusters: Clusters, matrix: np.ndarray) -> Transfer:
    """`matrix` (2, C, R) in receiver order → a Transfer with each side's columns grouped by cluster."""
    order, starts, out = [], [], np.empty_like(matrix)
    for side in range(2):
        members = clusters.side_cluster[:, side]
        key = np.where(members >= 0, members, clusters.count)
        perm = np.argsort(key, kind="stable")
        out[side] = matrix[side][:, perm]
        order.append(perm)
        starts.append(np.searchsorted(key[perm], np.arange(clusters.count + 1)))
    return Transfer(clusters, out, order, starts)


def albedo_transfer(t: Transfer, weight: np.ndarray) -> np.ndarray:
    """M_ρ (3, C, C): M[ch, c', c] = the flux cluster c' reflects in channel ch when cluster c emits one watt —
    Σ over c'’s voxel sides of albedo × area × T, one small product per cluster and side over its contiguous
    columns (all three channels at once: T is read once)."""
    count = t.clusters.count
    out = np.zeros((count, count, 3), np.float32)  # [c', c, ch]
    for side in range(2):
        w = weight[t.order[side]].astype(np.float32)
        starts = t.starts[side]
        for c in range(count):
            a, b = starts[c], starts[c + 1]
            if b > a:
                out[c] += t.matrix[side][:, a:b] @ w[a:b]
    return np.ascontiguousarray(out.transpose(2, 0, 1), np.float64)


def solve(t: Transfer, m_rho: np.ndarray, weight: np.ndarray, first: np.ndarray, world: np.ndarray | None,
          bounces: int, epsilon: float) -> tuple[np.ndarray, list]:
    """Irradiance summed over `bounces` passes, (2, R, 3) per side: the world's own (`world`, (2, R, 3) or None)
    plus T × the sources' flux summed over passes — `first` (C, 3) from the RSM, each further pass's the
    reflection of the one before (M_ρ). Stops once a pass's flux is below `epsilon` of the largest so far.
    Returns the totals and, per pass, its source flux."""
    phi = np.asarray(first, np.float64)
    total = phi.copy()
    passes = [float(phi.sum())]
    following = np.einsum("kij,jk->ik", m_rho, phi)
    if world is not None:
        following += reflect(t.clusters, weight, world)
    for _ in range(2, bounces + 1):
        phi = following
        passes.append(float(phi.sum()))
        total += phi
        if passes[-1] <= epsilon * max(passes):
            break
        following = np.einsum("kij,jk->ik", m_rho, phi)
    sums = total.T.astype(np.float32)  # (3, C)
    out = np.empty((2, t.matrix.shape[2], 3), np.float32)
    for side in range(2):
        out[side, t.order[side]] = (sums @ t.matrix[side]).T
    if world is not None:
        out += world
    return out, passes


def read_sides(state, cells: np.ndarray) -> np.ndarray:
    """(2, R, 3): the front / back irradiance textures of `state` (fine voxels) at `cells` (R, 3) xyz."""
    out = []
    for tex in (state.front, state.back):
        w, h, d = tex.size
        data = np.frombuffer(tex.read(), np.float32).reshape(d, h, w, 4)
        out.append(data[cells[:, 2], cells[:, 1], cells[:, 0], :3])
    return np.stack(out)


@dataclass
class SurfaceIrradiance:
    """What the flux lookup (lpv/lighting.glsl) reads of one cascade: irradiance per fine voxel and side."""
    grid: Grid
    front_total: object
    back_total: object

    def release(self):
        self.front_total.release()
        self.back_total.release()


def upload_sides(ctx, grid: Grid, fine: Grid, cells: np.ndarray, valid: np.ndarray,
                 sides: np.ndarray) -> SurfaceIrradiance:
    """Fine-voxel textures of (2, R, 3) irradiance at `cells`; a = 1 on voxels that receive (`valid`)."""
    import moderngl

    nx, ny, nz = fine.size
    textures = []
    for side in range(2):
        data = np.zeros((nz, ny, nx, 4), np.float32)
        data[cells[:, 2], cells[:, 1], cells[:, 0], :3] = np.where(valid[:, None], sides[side], 0.0)
        data[cells[:, 2], cells[:, 1], cells[:, 0], 3] = valid
        tex = ctx.texture3d((nx, ny, nz), 4, data.tobytes(), dtype="f4")
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        textures.append(tex)
    return SurfaceIrradiance(grid, *textures)
