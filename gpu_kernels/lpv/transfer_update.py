# SPDX-License-Identifier: GPL-3.0-or-later
"""The cached transport after a geometry edit (lpv/transfer.py): T updated from the one before it instead of built
anew. The clusters are re-made with the blocks they had, so clusters away from the edit come out the same; a pair
(cluster, receiver) is evaluated again only where the edit can change it — a new source or receiver, or a segment
through the box of the cells whose visibility planes changed (lpv/crossings.py) — and keeps its value otherwise.

The pairs to evaluate are listed first (the box test on the GPU, one bit per pair: box_pairs) and then evaluated one
per invocation (lpv/gather.glsl PAIRS). Skipping the others inside the full build's loop over sources saved nothing
on llvmpipe: a branch runs for every lane of a SIMD group whenever one lane takes it, so the skipped pairs cost what
evaluated ones do (the furnished room's update of 5% of its pairs took 35% of a full build's time). The list also
gives the share before any pair is evaluated, so an edit that changes most of T builds it anew without first paying
for an update (the courtyard's object move did both)."""
from __future__ import annotations

import numpy as np

from ..common.grid import Grid
from ..gl.bind import set_uniform
from .clusters import Clusters, make_clusters
from .transfer import cluster_order, dispatch_in_runs, kernel_program, receiver_rows, sorted_transfer

PAIRS_PER_DISPATCH = 1 << 20  # pairs evaluated per dispatch and listed at a time: 8 MiB read back, 16384 groups
# Sources per box_pairs dispatch: each invocation tests 32 receivers against each of them, and llvmpipe ends an
# invocation's loops after 65535 iterations in all (lpv/gather.vpls_per_dispatch).
MASK_SOURCES = 1024


def update_transfer(ctx, programs, gv, grid: Grid, occlusion: bool, prior, limit: float = 0.5):
    """The Transfer after a geometry edit, from `prior` (the one before it); None where the share of pairs to
    evaluate would reach `limit` (build T anew instead)."""
    new = make_clusters(gv.cells, gv.surface_normal, gv.surface_area, gv.fine, 0, block=prior.clusters.block,
                        positions=gv.positions, bounds=gv.bounds, detached=prior.clusters.detached)
    before, after = prior.rows, receiver_rows(gv)
    old_r = _match_receivers(before, after)
    old_c = _match(_cluster_rows(prior.clusters), _cluster_rows(new))
    gone = _match_receivers(after, before) < 0
    box = changed_box(np.concatenate([before[gone, :3], after[old_r < 0, :3]]), grid)
    fresh = (old_c < 0)[:, None] | (old_r < 0)[None, :]
    if box is not None:
        fresh |= box_pairs(ctx, programs, gv, new, box)
    per_source = np.count_nonzero(fresh, axis=1)
    share = int(per_source.sum()) / max(fresh.size, 1)
    if share >= limit:
        return None
    order, starts = cluster_order(new)
    columns = []
    matrix = np.empty((2, new.count, int(gv.surface_count)), np.float32)
    for side in range(2):  # columns in the new clusters' order: the kept pairs' old values, then the fresh ones
        old_column = np.empty(len(prior.order[side]), np.int64)
        old_column[prior.order[side]] = np.arange(len(old_column))
        columns.append(np.empty(len(order[side]), np.int64))
        columns[side][order[side]] = np.arange(len(order[side]))
        take_columns(prior.matrix[side], old_column[np.maximum(old_r[order[side]], 0)], matrix[side],
                     rows=np.maximum(old_c, 0))
    for first, last in source_chunks(per_source, PAIRS_PER_DISPATCH):  # the pair lists a chunk at a time
        sources, receivers = np.nonzero(fresh[first:last])
        sources += first
        values = evaluate_pairs(ctx, programs, gv, grid, new, occlusion, sources, receivers)
        for side in range(2):
            matrix[side][sources, columns[side][receivers]] = values[:, side]
    return sorted_transfer(new, matrix, order, starts, gv, grid, share, after)


def source_chunks(counts: np.ndarray, most: int) -> list:
    """[first, last) ranges of consecutive sources whose pairs (`counts` per source) add up to at most `most` each
    (or one source, if it alone has more): an update's pair list is made and evaluated one range at a time, so its
    host memory stays a few tens of MiB however large T is."""
    out, first, total = [], 0, 0
    for i, n in enumerate(counts):
        if total and total + n > most:
            out.append((first, i))
            first, total = i, 0
        total += int(n)
    if total:
        out.append((first, len(counts)))
    return out


def take_columns(src: np.ndarray, columns: np.ndarray, out: np.ndarray, rows: np.ndarray | None = None) -> None:
    """out[:, k] = src[rows][:, columns[k]] (`rows`: all of them where None), each run of consecutive columns copied
    as one block, rows and columns at once: an update's columns are the kept clusters' receivers in the order they
    had, a few hundred runs, where a column-by-column gather (np.take) cost 0.1 s a side in the furnished room, and
    gathering the rows first copied T once more."""
    if len(columns) == 0:
        return
    breaks = np.nonzero(np.diff(columns) != 1)[0] + 1
    if len(breaks) > len(columns) // 8:  # short runs: the gather is as fast
        np.take(src if rows is None else np.take(src, rows, axis=0), columns, axis=1, out=out)
        return
    for a, b in zip(np.concatenate([[0], breaks]), np.concatenate([breaks, [len(columns)]])):
        block = slice(columns[a], columns[a] + (b - a))
        out[:, a:b] = src[:, block] if rows is None else src[rows, block]


def box_pairs(ctx, programs, gv, clusters: Clusters, box: np.ndarray) -> np.ndarray:
    """(C, R) bool: whether the segment from cluster c's record to receiver r's centroid passes through `box`
    (2, 3) — where lpv/gather.glsl's kernel is evaluated (lpv/box_pairs.glsl)."""
    r, c = int(gv.surface_count), clusters.count
    words = -(-r // 32)
    out = np.zeros((c, r), bool)
    if r == 0 or c == 0:
        return out
    prog = programs.compute("lpv/box_pairs.glsl")
    sources = ctx.buffer(clusters.records.tobytes())
    sources.bind_to_storage_buffer(6)
    gv.receivers.bind_to_storage_buffer(10)
    set_uniform(prog, "u_surface_count", r)
    set_uniform(prog, "u_words", words)
    set_uniform(prog, "u_box_lo", tuple(float(v) for v in box[0]))
    set_uniform(prog, "u_box_hi", tuple(float(v) for v in box[1]))
    for first, count, data in dispatch_in_runs(ctx, prog, c, MASK_SOURCES, words, 4 * words):
        bits = np.frombuffer(data, np.uint32).reshape(count, words)
        out[first:first + count] = np.unpackbits(bits.view(np.uint8), axis=1, bitorder="little")[:, :r]
    sources.release()
    return out


def evaluate_pairs(ctx, programs, gv, grid: Grid, clusters: Clusters, occlusion: bool, sources: np.ndarray,
                   receivers: np.ndarray) -> np.ndarray:
    """(N, 2) float32: lpv/gather.glsl's kernel (front, back) for each pair (sources[k], receivers[k])."""
    out = np.zeros((len(sources), 2), np.float32)
    if len(sources) == 0:
        return out
    prog, buffers = kernel_program(ctx, programs, gv, grid, clusters, occlusion, {"PAIRS": 1})
    pairs = np.empty((len(sources), 2), np.int32)
    pairs[:, 0], pairs[:, 1] = sources, receivers
    pairs = ctx.buffer(pairs.tobytes())
    pairs.bind_to_storage_buffer(11)
    for first, count, data in dispatch_in_runs(ctx, prog, len(sources), PAIRS_PER_DISPATCH, 0, 8,
                                               ("u_pair_first", "u_pair_count")):
        out[first:first + count] = np.frombuffer(data, np.float32).reshape(count, 2)
    for buffer in buffers + [pairs]:
        buffer.release()
    return out


def _match(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """For each row of `new` (structured or 2-D), the index of an identical row of `old`, or −1."""
    old_keys = {row.tobytes(): i for i, row in enumerate(old)}
    return np.array([old_keys.get(row.tobytes(), -1) for row in new], np.int64)


def _cluster_rows(clusters: Clusters) -> np.ndarray:
    """(C, bytes) uint8 per cluster: its record and the octagon its surfaces span (the kernel's near field)."""
    return np.concatenate([clusters.records.view(np.uint8).reshape(clusters.count, -1),
                           np.ascontiguousarray(clusters.polygon).view(np.uint8).reshape(clusters.count, -1)], axis=1)


def _match_receivers(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """_match for transfer.receiver_rows, vectorised: a receiver is one (voxel, axis), so rows are paired by that key
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
