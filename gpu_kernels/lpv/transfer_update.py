# SPDX-License-Identifier: GPL-3.0-or-later
"""The cached transport after a geometry edit (lpv/transfer.py): T updated from the one before it instead of built
anew. The clusters are re-made with the blocks they had, so clusters away from the edit come out the same; a pair
(cluster, receiver) is evaluated again only where the edit can change it — a new source or receiver, or a segment
through one of a few boxes around the cells whose visibility planes changed (lpv/crossings.py) — and keeps its value
otherwise. "Changed" means by more than float rounding (NORMAL_TOLERANCE, EXTENT_TOLERANCE).

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
from . import crossings
from .clusters import Clusters, make_clusters
from .transfer import cluster_order, dispatch_in_runs, empty_matrix, kernel_program, receiver_rows, sorted_transfer

PAIRS_PER_DISPATCH = 1 << 20  # pairs evaluated per dispatch and listed at a time: 8 MiB read back, 16384 groups
# box_pairs' invocations per dispatch: one per source and word of 32 receivers (the most work groups of 64 a
# dispatch may have). Looping over a run of sources in each invocation instead (one per word) kept only a few work
# groups busy and ran into llvmpipe's cap on an invocation's loop iterations (65535 in all, then it silently stops:
# 1024 sources against eight boxes listed half the pairs that cross them).
MASK_INVOCATIONS = 65535 * 64
MAX_BOXES = 8  # boxes around the changed cells (changed_boxes); lpv/box_pairs.glsl holds one more
# The share of pairs to evaluate from which T is built anew instead. A pair costs the update about what it costs a
# build (measured on llvmpipe: 0.20–0.25 µs evaluated one per invocation, 0.27–0.29 µs in a build), and the update
# adds listing the pairs and copying the kept ones (a tenth of a build or less): at half of T it was still two
# thirds of a build (the courtyard's floor lifted 5 cm, 52–58% of its pairs: 1.45–1.50 s against 2.1–2.3 s).
REBUILD_SHARE = 0.9
# What an edit leaves the same, to float rounding: a receiver's or cluster's row is kept where no entry moved by more
# than these (normals: unit; areas: × the fine voxel's face; positions: × its edge). Moving an object re-derives its
# triangles in world space, and the float32 arithmetic of its voxels' areas, normals and centroids changes in the
# last bits (measured: 1e-7 of a unit normal, 3e-8 m of a centroid) where its surfaces did not move: compared bit
# for bit, every voxel of the Cornell box's lifted block came out changed and every segment across it was evaluated
# again. The kept values then differ from a build's by what such rounding does to the kernel (the Cornell box's
# Diffuse Indirect after a 5 cm lift: within 7e-5 of its mean at every pixel; bitwise equal when compared exactly).
NORMAL_TOLERANCE = 1e-5
EXTENT_TOLERANCE = 1e-4


def update_transfer(ctx, programs, gv, grid: Grid, occlusion: bool, prior, limit: float | None = None, spare=None,
                    most_clusters: int | None = None):
    """The Transfer after a geometry edit, from `prior` (the one before it), its T written into `spare`'s memory
    where it fits (transfer.empty_matrix); None where the share of pairs to evaluate would reach `limit` (default
    REBUILD_SHARE), or the clusters re-made with the prior's blocks would outnumber `most_clusters` (the memory
    budget: a build picks larger blocks): build T anew instead."""
    new = make_clusters(gv.cells, gv.surface_normal, gv.surface_area, gv.fine, 0, block=prior.clusters.block,
                        positions=gv.positions, bounds=gv.bounds, detached=prior.clusters.detached)
    if most_clusters is not None and new.count > most_clusters:
        return None
    before, after = prior.rows, receiver_rows(gv)
    cell = float(gv.fine.cell)
    old_r = _match_receivers(before, after, cell)
    old_c = _match_clusters(prior.clusters, new, cell)
    gone = _match_receivers(after, before, cell) < 0
    cells = changed_cells(np.concatenate([before[gone, :3], after[old_r < 0, :3]]), prior.crossings, gv.crossings)
    boxes = changed_boxes(cells, grid)
    fresh = (old_c < 0)[:, None] | (old_r < 0)[None, :]
    if boxes is not None:
        fresh |= box_pairs(ctx, programs, gv, new, boxes)
    per_source = np.count_nonzero(fresh, axis=1)
    share = int(per_source.sum()) / max(fresh.size, 1)
    if share >= (REBUILD_SHARE if limit is None else limit):
        return None
    order, starts = cluster_order(new)
    columns = []
    r = int(gv.surface_count)  # room to grow within the budget most_clusters stands for
    matrix = empty_matrix((2, new.count, r), spare, None if most_clusters is None else 2 * most_clusters * r)
    for side in range(2):  # columns in the new clusters' order: the kept pairs' old values, then the fresh ones
        old_column = np.empty(len(prior.order[side]), np.int64)
        old_column[prior.order[side]] = np.arange(len(old_column))
        columns.append(np.empty(len(order[side]), np.int64))
        columns[side][order[side]] = np.arange(len(order[side]))
        take_columns(prior.matrix[side], old_column[np.maximum(old_r[order[side]], 0)], matrix[side],
                     rows=np.maximum(old_c, 0))
    for first, last in source_chunks(per_source, PAIRS_PER_DISPATCH):  # the pair lists a chunk at a time
        sources, receivers = np.divmod(np.flatnonzero(fresh[first:last]), fresh.shape[1])  # 4× a 2-D np.nonzero
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
    """out[i] = src[rows[i], columns] (`rows`: all of them where None), a row at a time: a gather within one
    contiguous row into another makes no temporary (mode "clip": the indices are valid, and the default mode
    buffers `out`). Copying each run of consecutive columns for all rows at once made a temporary per run, and numpy
    asks the kernel for huge pages for those over 4 MiB: their page faults cost the Cornell box's update 0.1–0.2 s,
    three to seven times the copy itself; a column-at-a-time gather over the whole matrix was slower still."""
    for i, r in enumerate(range(len(out)) if rows is None else rows):
        np.take(src[r], columns, out=out[i], mode="clip")


def box_pairs(ctx, programs, gv, clusters: Clusters, boxes: np.ndarray) -> np.ndarray:
    """(C, R) bool: whether the segment from cluster c's record to receiver r's centroid passes through one of
    `boxes` (K, 2, 3), K ≤ MAX_BOXES — where lpv/gather.glsl's kernel is evaluated (lpv/box_pairs.glsl)."""
    r, c = int(gv.surface_count), clusters.count
    words = -(-r // 32)
    out = np.zeros((c, r), bool)
    if r == 0 or c == 0:
        return out
    prog = programs.compute("lpv/box_pairs.glsl")
    sources = ctx.buffer(clusters.records.tobytes())
    sources.bind_to_storage_buffer(6)
    spans = ctx.buffer(word_spans(gv.positions, words).tobytes())
    spans.bind_to_storage_buffer(7)
    gv.receivers.bind_to_storage_buffer(10)
    set_uniform(prog, "u_margin", 1e-4 * float(np.abs(boxes).max()) + 1e-6)
    set_uniform(prog, "u_surface_count", r)
    set_uniform(prog, "u_words", words)
    boxes = np.concatenate([[[boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)]], boxes])  # the box around them first
    set_uniform(prog, "u_box_count", len(boxes))
    padded = np.zeros((2, MAX_BOXES + 1, 3))
    padded[:, :len(boxes)] = boxes.transpose(1, 0, 2)
    set_uniform(prog, "u_box_lo", [tuple(float(v) for v in corner) for corner in padded[0]])
    set_uniform(prog, "u_box_hi", [tuple(float(v) for v in corner) for corner in padded[1]])
    per_run = max(1, MASK_INVOCATIONS // words)
    for first, count, data in dispatch_in_runs(ctx, prog, c, per_run, min(per_run, c) * words, 4 * words):
        bits = np.frombuffer(data, np.uint32).reshape(count, words)
        out[first:first + count] = np.unpackbits(bits.view(np.uint8), axis=1, bitorder="little")[:, :r]
    sources.release()
    spans.release()
    return out


def word_spans(positions: np.ndarray, words: int) -> np.ndarray:
    """(words, 2, 4) float32: the box (lo, hi) around each run of 32 receivers' centroids (`positions`, (R, 3), as
    the receivers' buffer holds them): lpv/box_pairs.glsl skips a source's 32 tests where the box around the source
    and those centroids meets no changed box. Receivers come in voxel order, so a run is a short strip of a
    surface, and a small edit's boxes miss most of them."""
    p = np.asarray(positions, np.float32).reshape(-1, 3)
    p = np.concatenate([p, np.repeat(p[-1:], words * 32 - len(p), axis=0)]).reshape(words, 32, 3)
    out = np.zeros((words, 2, 4), np.float32)
    out[:, 0, :3], out[:, 1, :3] = p.min(axis=1), p.max(axis=1)
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


def _match_clusters(old: Clusters, new: Clusters, cell: float) -> np.ndarray:
    """For each cluster of `new`, the index of the cluster of `old` with its key whose record and octagon are the
    same within the tolerances, or −1."""
    rows_old, rows_new = _cluster_rows(old), _cluster_rows(new)
    order = np.argsort(old.key, kind="stable")
    first = np.searchsorted(old.key[order], new.key, "left")
    count = np.searchsorted(old.key[order], new.key, "right") - first
    pair_new = np.repeat(np.arange(new.count), count)
    pair_old = order[np.repeat(first - np.cumsum(count) + count, count) + np.arange(int(count.sum()))]
    same = _within(rows_old[pair_old], rows_new[pair_new], _cluster_tolerance(cell))
    out = np.full(new.count, np.iinfo(np.int64).max, np.int64)
    np.minimum.at(out, pair_new[same], pair_old[same])
    return np.where(out == np.iinfo(np.int64).max, -1, out)


def _cluster_rows(clusters: Clusters) -> np.ndarray:
    """(C, 44) float64 per cluster: its record (position, normal and area, flux) and the octagon its surfaces span
    (the kernel's near field)."""
    r = clusters.records
    return np.concatenate([r["position"], r["normal"], r["flux"], clusters.polygon.reshape(clusters.count, -1)],
                          axis=1).astype(np.float64)


def _cluster_tolerance(cell: float) -> np.ndarray:
    """_cluster_rows' tolerance per column: record position xyzw, normal xyz and area, flux; corners xyz and w (the
    first corner's w a flag, the second's the octagon's area)."""
    length, area = EXTENT_TOLERANCE * cell, EXTENT_TOLERANCE * cell * cell
    corners = np.tile([length, length, length, 0.0], (8, 1))
    corners[1, 3] = area
    return np.concatenate([[length] * 4, [NORMAL_TOLERANCE] * 3, [area], [0.0] * 4, corners.ravel()])


def _receiver_tolerance(cell: float) -> np.ndarray:
    """transfer.receiver_rows' tolerance per column: voxel and axis, normal, area, position, box (lo, hi)."""
    length = EXTENT_TOLERANCE * cell
    return np.array([0.0] * 4 + [NORMAL_TOLERANCE] * 3 + [EXTENT_TOLERANCE * cell * cell] + [length] * 9)


def _within(old: np.ndarray, new: np.ndarray, tolerance: np.ndarray) -> np.ndarray:
    """Per row: whether no entry of `new` differs from `old`'s by more than its column's tolerance."""
    return (np.abs(old - new) <= tolerance).all(axis=1)


def _match_receivers(old: np.ndarray, new: np.ndarray, cell: float) -> np.ndarray:
    """For each row of `new` (transfer.receiver_rows), the index of the row of `old` with the same key (a receiver
    is one (voxel, axis): sorted search) that is the same within the tolerances, or −1."""
    def key(rows):
        c = rows[:, :4].astype(np.int64)
        return ((c[:, 2] * (1 << 20) + c[:, 1]) * (1 << 20) + c[:, 0]) * 4 + c[:, 3]
    old_key, new_key = key(old), key(new)
    order = np.argsort(old_key, kind="stable")
    at = np.minimum(np.searchsorted(old_key[order], new_key), max(len(old) - 1, 0))
    if len(old) == 0:
        return np.full(len(new), -1, np.int64)
    index = order[at]
    same = (old_key[index] == new_key) & _within(old[index], new, _receiver_tolerance(cell))
    return np.where(same, index, -1)


def changed_cells(moved: np.ndarray, before: dict | None, after: dict | None) -> np.ndarray:
    """(N, 3) xyz of the LPV cells whose visibility planes an edit changed: those holding the fine voxels `moved`
    (voxels that appeared, vanished, or got another normal, area or position; LPV cell c holds fine voxels 2c + 1
    and 2c + 2 along each axis), and those whose crossing_layers arrays (`before`, `after`; None: unknown) differ by
    more than EXTENT_TOLERANCE (cells, or shares of a cell): the planes are made with thresholds (one plane or
    three, one layer or two), and a voxel's rounding noise can tip one."""
    cells = [np.floor((np.asarray(moved, np.float64).reshape(-1, 3) - 1) / 2).astype(np.int64)]
    if before is not None and after is not None:
        if any(before.get(name) is None or before[name].shape != a.shape for name, a in after.items()):
            shape = after["coverage"].shape[2::-1]
            return np.indices(shape).reshape(3, -1).T  # another grid: every cell
        # an empty cell's w is its distance to the nearest surface (crossings.mark_empty_space): how far a ray may
        # skip, which changes no visibility
        empty = ~crossings.occupied(before["coverage"]) & ~crossings.occupied(after["coverage"])
        for name, a in after.items():
            differ = np.abs(a - before[name]) > EXTENT_TOLERANCE
            if name == "coverage":
                differ[..., 3] &= ~empty
            cells.append(np.argwhere(differ.any(axis=-1))[:, ::-1])
    return np.unique(np.concatenate(cells), axis=0)


def changed_boxes(cells: np.ndarray, grid: Grid, most: int = MAX_BOXES):
    """Boxes (K, 2, 3), K ≤ `most`, around the LPV `cells` (N, 3) an edit changed (changed_cells); None when it
    changed none. One box around them all held, for a block lifted 5 cm, the block's whole height, where only its
    top and bottom changed: every segment across its sides was evaluated again."""
    if len(cells) == 0:
        return None
    origin = np.asarray(grid.origin)
    return np.stack([np.stack([origin + g.min(axis=0) * grid.cell, origin + (g.max(axis=0) + 1) * grid.cell])
                     for g in split_cells(cells, most)])


def split_cells(cells: np.ndarray, most: int) -> list:
    """At most `most` groups of `cells` (N, 3) int whose boxes hold fewer cells in all than one box around them:
    the group whose box holds the most cells that are not its own is cut across an axis where the two boxes left
    hold the fewest cells, until no cut leaves fewer or there are `most` groups."""
    groups, done = [cells], []
    while groups and len(groups) + len(done) < most:
        waste = [_volume(g) - len(g) for g in groups]
        g = groups.pop(int(np.argmax(waste)))
        halves = _best_cut(g) if max(waste) > 0 else None
        if halves is None:
            done.append(g)
        else:
            groups.extend(halves)
    return groups + done


def _volume(cells: np.ndarray) -> int:
    """Cells in the box around `cells`."""
    return int(np.prod(cells.max(axis=0) - cells.min(axis=0) + 1))


def _best_cut(cells: np.ndarray):
    """The two groups of `cells`, split across one axis between two of their coordinates, whose boxes hold the
    fewest cells together; None where none holds fewer than the one box around them."""
    best, volume = None, _volume(cells)
    for axis in range(3):
        s = cells[np.argsort(cells[:, axis], kind="stable")]
        cut = np.nonzero(np.diff(s[:, axis]))[0] + 1
        if len(cut) == 0:
            continue
        lo, hi = np.minimum.accumulate(s, axis=0), np.maximum.accumulate(s, axis=0)
        back_lo, back_hi = np.minimum.accumulate(s[::-1], axis=0)[::-1], np.maximum.accumulate(s[::-1], axis=0)[::-1]
        total = np.prod(hi[cut - 1] - lo[cut - 1] + 1, axis=1) + np.prod(back_hi[cut] - back_lo[cut] + 1, axis=1)
        k = int(np.argmin(total))
        if total[k] < volume:
            best, volume = (s[:cut[k]], s[cut[k]:]), int(total[k])
    return best
