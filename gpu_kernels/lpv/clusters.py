# SPDX-License-Identifier: GPL-3.0-or-later
"""The cached LPV transport's sources (lpv/transfer.py): the surface voxels' sides grouped, once per geometry, into
clusters — S×S×S blocks of fine voxels, split by the dominant axis of each side's normal (a floor and the wall
beside it stay apart), by plane (a rug and the floor under it) and by connectivity (two rooms' floors in one
block, on either side of a partition) — with area-weighted positions and normals. Sides with the whole scene
behind them get none. And the RSM's VPL flux binned into them (bin_flux): each watt kept or counted as escaped.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from .gather import VPL_DTYPE

# RSM records binned one per texel up to this many texels (bin_flux): merging texels first (lpv/inject.glsl's k×k
# blocks) pools a block's surfaces — a sunlit wall's outside with the floor inside the window beside it — at a mean
# position that can fall in another voxel, and which blocks pool depends on the atlas the lights make: the window
# room's first bounce with its sun and sky together was 38 W, 1.6× the sum of either alone (9 + 15); per texel it
# is 28.7 = 9.1 + 19.6, linear in the lights as the transfer assumes. 2^20 texels bin in well under a second.
TEXEL_RECORDS = 1 << 20
OWN_ALIGN = 0.5  # cos 60°: own_side


@dataclass
class Clusters:
    """Geometry-only sources: the cluster of each surface voxel's front / back side, and each cluster's VPL record
    (its core's centroid and mean side normal, w = total area), in order of (block and side key, plane offset)."""
    block: int  # S: fine voxels per block side
    side_cluster: np.ndarray  # (R, 2) int: cluster of the front / back side, −1 where it emits nowhere
    records: np.ndarray  # (C,) VPL_DTYPE, flux 0
    key: np.ndarray  # (C,) block index × 6 + side (side_of) of each cluster, ascending
    offsets: np.ndarray  # (C, 2) min / max plane offset n·x (m) of its voxels' centres
    box: np.ndarray  # (C, 2, 3) min / max corner of its voxels' centres
    polygon: np.ndarray  # (C, 8, 4) the octagon its surfaces span (polygons; lpv/gather.glsl polygon_kernel)
    fine: Grid
    lo: np.ndarray  # the surface voxels' centres' bounding box (faces_something)
    hi: np.ndarray
    detached: bool = False  # detached pieces kept as clusters of their own (_blocks), as an update must again

    @property
    def count(self) -> int:
        return len(self.records)


def side_of(normals: np.ndarray) -> np.ndarray:
    """0..5: the dominant axis of each normal and its sign (+x, −x, +y, −y, +z, −z)."""
    axis = np.argmax(np.abs(normals), axis=1)
    return 2 * axis + (normals[np.arange(len(normals)), axis] < 0)


def block_keys(points: np.ndarray, normals: np.ndarray, fine: Grid, block: int) -> np.ndarray:
    """Block index × 6 + side of oriented points (world positions, unit normals)."""
    size = np.asarray(fine.size)
    f = np.clip(np.floor((points - np.asarray(fine.origin)) / fine.cell).astype(np.int64), 0, size - 1)
    b = f // block
    blocks = -(-size // block)
    return ((b[:, 2] * blocks[1] + b[:, 1]) * blocks[0] + b[:, 0]) * 6 + side_of(normals)


def faces_something(points: np.ndarray, normals: np.ndarray, lo: np.ndarray, hi: np.ndarray, h: float) -> np.ndarray:
    """Whether any of the box [lo, hi] lies in front of each oriented point by more than the kernel's own-surface
    height (lpv/gather.glsl: ½ h·|n|₁) plus a voxel: a side with the whole scene behind it — the outside of a
    room's boundary walls, a roof's top — sends light to no receiver, so it needs no source (or column of T)."""
    corner = np.where(normals > 0, hi, lo)  # the box's support point along each normal
    reach = np.einsum("ij,ij->i", normals, corner - points)
    return reach > h * (0.5 * np.abs(normals).sum(axis=1) + 1.0)


def _absorb_small(piece: np.ndarray, parent: np.ndarray, smallest: int, offset: np.ndarray | None = None,
                  reach: float = np.inf, points: np.ndarray | None = None) -> np.ndarray:
    """Pieces (labels per side) of fewer than `smallest` sides join the largest piece of their `parent` group —
    an edge voxel whose normal leans away from its neighbours' is no surface of its own — if its plane (mean
    `offset`) lies within `reach` of theirs: a pillar's inner face is not its outer face's, however small. With
    `points` (per side), only a piece whose mean point lies within `reach` of the box of the largest piece's points:
    a detached piece elsewhere in the block (a strip of floor cut off by a wall, a tree's crown beside a façade)
    stays a surface of its own, where it is."""
    sizes = np.bincount(piece)
    largest = np.full(int(parent.max(initial=-1)) + 1, -1)
    by_size = np.lexsort((sizes[piece], parent))  # per parent, ascending size: the last one written wins
    largest[parent[by_size]] = piece[by_size]
    target = largest[parent]
    near = True
    if offset is not None:
        mean = np.bincount(piece, offset) / np.maximum(sizes, 1)
        near = np.abs(mean[piece] - mean[target]) <= reach
    if points is not None:
        lo, hi, n = np.full((len(sizes), 3), np.inf), np.full((len(sizes), 3), -np.inf), np.maximum(sizes, 1)
        np.minimum.at(lo, piece, points), np.maximum.at(hi, piece, points)
        at = np.stack([np.bincount(piece, points[:, i], len(sizes)) / n for i in range(3)], 1)[piece]
        near = np.all((at >= lo[target] - reach) & (at <= hi[target] + reach), axis=1)
    return np.where((sizes[piece] < smallest) & near, target, piece)


def _group(key: np.ndarray, offset: np.ndarray, gap: float, pairs: np.ndarray, smallest: int,
           points: np.ndarray | None) -> tuple:
    """(cluster index of every side, whether it is of its cluster's core): sides of one key (block and side), in one
    plane — sorted by plane offset, a new plane where it jumps by more than `gap` (a thin wall's faces, a rug on a
    floor) — and connected through `pairs` of neighbouring sides (two rooms' floors cut apart by a partition).
    Pieces of fewer than `smallest` sides (_absorb_small) join their plane's largest piece but not its core (a tree's
    crown in a façade's block); with `points` (per side), only within that piece's box, else they stay clusters of
    their own. Clusters are numbered by (key, plane offset)."""
    order = np.lexsort((offset, key))
    k, d = key[order], offset[order]
    new = np.ones(len(order), bool)
    new[1:] = (k[1:] != k[:-1]) | (d[1:] - d[:-1] > gap)
    plane = np.empty(len(order), np.int64)
    plane[order] = np.cumsum(new) - 1
    plane = _absorb_small(plane, np.unique(key, return_inverse=True)[1].reshape(-1), smallest, offset, 2 * gap)
    a, b = pairs[plane[pairs[:, 0]] == plane[pairs[:, 1]]].T if len(pairs) else (np.zeros(0, int),) * 2
    label = np.arange(len(key))
    while True:  # connected components: each side takes the smallest label it is joined to
        low = np.minimum(label[a], label[b])
        previous = label.copy()
        np.minimum.at(label, a, low)
        np.minimum.at(label, b, low)
        label = label[label]
        if np.array_equal(label, previous):
            break
    joined = _absorb_small(label, plane, smallest, reach=gap if points is not None else np.inf, points=points)
    roots = np.unique(joined)
    rank = np.empty(len(roots), np.int64)
    rank[np.lexsort((offset[roots], key[roots]))] = np.arange(len(roots))
    return rank[np.searchsorted(roots, joined)], joined == label


def partitioned(cells: np.ndarray, normals: np.ndarray, positions: np.ndarray, pairs: np.ndarray,
                fine: Grid) -> np.ndarray:
    """Per pair of neighbouring receivers (`pairs` (P, 2) indices of `cells`, unit `normals`, `positions`): whether
    the plane of a receiver of another axis in either's voxel passes between them — a wall thinner than a voxel
    standing on a floor that runs on under it, or meeting a wall that runs on beside it. Across it the two are
    parts of two rooms: joined in one cluster, the lit room's light would leave from the dark room's side."""
    nx, ny, _ = (int(n) for n in fine.size)
    lin = (cells[:, 2].astype(np.int64) * ny + cells[:, 1]) * nx + cells[:, 0]
    voxels, slot = np.unique(lin, return_inverse=True)
    planes = np.full((len(voxels), 3), np.nan)  # per voxel, per axis: where its receiver of that axis lies
    axis = np.argmax(np.abs(normals), axis=1)
    planes[slot.reshape(-1), axis] = positions[np.arange(len(cells)), axis]
    a, b = pairs[:, 0], pairs[:, 1]
    tolerance = 0.1 * fine.cell
    cut = np.zeros(len(pairs), bool)
    for voxel in (slot.reshape(-1)[a], slot.reshape(-1)[b]):
        q = planes[voxel]  # (P, 3)
        da, db = positions[a] - q, positions[b] - q
        with np.errstate(invalid="ignore"):
            cut |= np.any((da * db < 0) & (np.abs(da) > tolerance) & (np.abs(db) > tolerance), axis=1)
    return cut


def neighbour_pairs(cells: np.ndarray, sides: np.ndarray, size: tuple) -> np.ndarray:
    """(P, 2) indices of entries (voxel `cells` (N, 3), `sides` (N,) 0..5) whose voxels touch (26-neighbours)
    and whose sides match."""
    nx, ny, nz = (int(n) for n in size)
    lin = ((cells[:, 2] * ny + cells[:, 1]) * nx + cells[:, 0]) * 6 + sides
    order = np.argsort(lin)
    sorted_lin = lin[order]
    out = []
    for dz, dy, dx in [(dz, dy, dx) for dz in (-1, 0, 1) for dy in (-1, 0, 1) for dx in (-1, 0, 1)
                       if (dz, dy, dx) > (0, 0, 0)]:  # half the neighbourhood: each pair once
        moved = cells + (dx, dy, dz)
        inside = np.all((moved >= 0) & (moved < (nx, ny, nz)), axis=1)
        target = lin + ((dz * ny + dy) * nx + dx) * 6
        at = np.minimum(np.searchsorted(sorted_lin, target), len(lin) - 1)
        hit = inside & (sorted_lin[at] == target)
        out.append(np.stack([np.nonzero(hit)[0], order[at[hit]]], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2), np.int64)


def make_clusters(cells: np.ndarray, normals: np.ndarray, areas: np.ndarray, fine: Grid, budget: int,
                  block: int | None = None, positions: np.ndarray | None = None,
                  bounds: tuple | None = None, detached: bool | None = None) -> Clusters:
    """Cluster the surface voxels' sides (cells (R, 3) xyz, mean normals (R, 3), areas (R,); `positions` (R, 3) and
    `bounds` where their surfaces lie and the boxes they span, else the voxels' centres and boxes) into at most
    `budget` clusters: the smallest block side S (from 2) whose clusters fit, or the S = `block` and `detached` an
    update had (_blocks), so clusters away from the edit stay the same. A cluster's VPL record: its core sides'
    area-weighted position and mean normal (_group), the area of all its sides; its octagon spans its core's
    surfaces, its box all its voxels' centres. Sides facing nothing (`faces_something`) get none."""
    lengths = np.linalg.norm(normals, axis=1)
    valid = (areas > 0) & (lengths > 0)
    unit = normals / np.maximum(lengths, 1e-30)[:, None]
    centre = np.asarray(fine.origin) + (cells + 0.5) * fine.cell
    lo, hi = (centre.min(axis=0), centre.max(axis=0)) if len(centre) else (np.zeros(3), np.zeros(3))
    side_n = np.stack([unit, -unit], axis=1).reshape(-1, 3)  # voxel r's front at 2r, back at 2r + 1
    voxel = np.repeat(centre, 2, axis=0)
    pos = voxel if positions is None else np.repeat(np.asarray(positions, np.float64), 2, axis=0)
    emits = np.repeat(valid, 2) & faces_something(pos, side_n, lo, hi, fine.cell)
    use = np.nonzero(emits)[0]
    offset = np.einsum("ij,ij->i", side_n[use], pos[use])
    pairs = neighbour_pairs(cells[use // 2], side_of(side_n[use]), fine.size)
    if positions is not None and len(pairs):
        pairs = pairs[~partitioned(cells, unit, np.asarray(positions, np.float64), use[pairs] // 2, fine)]
    block, key, index, core, detached = _blocks(pos[use], side_n[use], offset, pairs, voxel[use], fine, budget,
                                                block, detached)
    count = int(index.max()) + 1 if len(index) else 0
    sides = np.full(2 * len(cells), -1, np.int64)
    sides[use] = index
    area = np.repeat(areas, 2)[use].astype(np.float64)
    records = np.zeros(count, VPL_DTYPE)
    total, shape = np.bincount(index, area, count), np.bincount(index, area * core, count)
    for i in range(3):  # where it lies and faces: its core's (a detached bit of it would pull it off its plane)
        records["position"][:, i] = np.bincount(index, area * core * pos[use, i], count) / np.maximum(shape, 1e-30)
        records["normal"][:, i] = np.bincount(index, area * core * side_n[use, i], count)
    n = records["normal"][:, :3] / np.maximum(shape, 1e-30)[:, None]  # the mean side normal: length 1 if planar
    records["normal"][:, :3] = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    records["normal"][:, 3] = total
    records["position"][:, 3] = 1.0
    order = np.argsort(index, kind="stable")
    first = order[np.searchsorted(index[order], np.arange(count))]
    offsets = np.stack([np.full(count, np.inf), np.full(count, -np.inf)], axis=1)
    np.minimum.at(offsets[:, 0], index, offset)
    np.maximum.at(offsets[:, 1], index, offset)
    box = np.stack([np.full((count, 3), np.inf), np.full((count, 3), -np.inf)], axis=1)
    np.minimum.at(box[:, 0], index, voxel[use])
    np.maximum.at(box[:, 1], index, voxel[use])
    side_lo, side_hi = (voxel - 0.5 * fine.cell, voxel + 0.5 * fine.cell) if bounds is None else \
        (np.repeat(np.asarray(b, np.float64), 2, axis=0) for b in bounds)
    polygon = polygons(records, n, index[core], side_lo[use][core], side_hi[use][core], fine.cell)
    return Clusters(block, sides.reshape(-1, 2), records, key[first], offsets, box, polygon, fine, lo, hi, detached)


def _blocks(pos, side_n, offset, pairs, points, fine: Grid, budget: int, block: int | None, detached: bool | None):
    """(block side S, keys, cluster index and core per side, detached) for make_clusters: the smallest S whose
    clusters fit `budget` with detached pieces joined to their plane's largest (_group without points), then those
    pieces kept as clusters of their own where that still fits (a strip of floor cut off by a wall: joined, its
    light left from the floor beyond). An update gives the S and `detached` it had."""
    fixed, block, gap = block is not None, block or 2, 0.5 * fine.cell
    while True:
        key = block_keys(pos, side_n, fine, block)
        if fixed and detached:  # an update of clusters that kept their detached pieces: that grouping alone
            return (block, key, *_group(key, offset, gap, pairs, max(2, block * block // 8), points), True)
        index, core = _group(key, offset, gap, pairs, max(2, block * block // 8), None)
        if fixed or (int(index.max()) + 1 if len(index) else 0) <= budget or block >= max(fine.size):
            break
        block += 1
    if detached is False:
        return block, key, index, core, False
    kept, kept_core = (index, core) if core.all() else _group(key, offset, gap, pairs, max(2, block ** 2 // 8), points)
    if detached or (int(kept.max()) + 1 if len(kept) else 0) <= budget:
        return block, key, kept, kept_core, True
    return block, key, index, core, False



AXIS_PLANE = 0.985  # cos 10°: a cluster whose normal lies this near an axis takes that axis' plane as its frame
PLANAR = 0.985  # a cluster whose sides' area-weighted mean normal is this long (10° of spread) lies in one plane


def polygons(records: np.ndarray, mean_normal: np.ndarray, index: np.ndarray, lo: np.ndarray, hi: np.ndarray,
             cell: float) -> np.ndarray:
    """(C, 8, 4) float32 per cluster: the corners, in order, of the octagon in its plane that holds its sides'
    surfaces (boxes `lo`, `hi` (N, 3) of the sides of cluster `index`) — lpv/gather.glsl's near field. First corner's
    w: 1 where the cluster is planar, else 0; second corner's w: the octagon's area.

    The plane passes through the cluster's centroid, across its normal — or across the axis it lies within 10° of
    (AXIS_PLANE), with the other two axes as its frame; else one frame axis lies across the axis the normal leans
    least along (a vertical wall at any angle: horizontal and vertical). Each side's surfaces span, along a frame
    axis t, Σ_i min / max(t_i·lo_i, t_i·hi_i) (exact for a planar piece, whose box's other corners project inside
    its span); the octagon is where the pieces' spans along the frame's axes and its two diagonals hold (an
    8-DOP): a rectangle where the surfaces fill one; where a wall at an angle cuts a block of floor, its diagonal
    edge keeps most of the floor's rectangle that lies beyond the wall out (a rectangle there put 4% of the floor's
    light on the wall's outside in a closed box turned 30°).

    Planar only where the sides' normals agree (PLANAR), whatever axis their mean lies along: the inside of a
    sphere's top, a cap whose mean normal is −z, spans in its mean plane a square wider than the sphere there, and
    as that square it lit the outside of the sphere's top from within (tests/gpu/test_lpv_near_field.py)."""
    count = len(records)
    unit = records["normal"][:, :3].astype(np.float64)
    dominant = np.argmax(np.abs(unit), axis=1)
    axis_plane = np.abs(unit[np.arange(count), dominant]) >= AXIS_PLANE
    eye = np.eye(3)
    t1 = np.cross(unit, eye[np.argmin(np.abs(unit), axis=1)])
    t1 /= np.maximum(np.linalg.norm(t1, axis=1, keepdims=True), 1e-30)
    t2 = np.cross(unit, t1)
    t1 = np.where(axis_plane[:, None], eye[(dominant + 1) % 3], t1)
    t2 = np.where(axis_plane[:, None], eye[(dominant + 2) % 3], t2)
    span = np.zeros((count, 4, 2))  # along t1, t2, t1 + t2, t1 − t2: min, max
    span[..., 0], span[..., 1] = np.inf, -np.inf
    piece = []
    for t in (t1, t2):
        a, b = t[index] * lo, t[index] * hi
        piece.append((np.minimum(a, b).sum(axis=1), np.maximum(a, b).sum(axis=1)))
    (u0, u1), (v0, v1) = piece
    for k, (low, high) in enumerate(((u0, u1), (v0, v1), (u0 + v0, u1 + v1), (u0 - v1, u1 - v0))):
        np.minimum.at(span[:, k, 0], index, low)
        np.maximum.at(span[:, k, 1], index, high)
    (a0, a1), (b0, b1), (s0, s1), (d0, d1) = span.transpose(1, 2, 0)
    corners = np.stack([np.stack(c, axis=1) for c in (  # (u, v), counter-clockwise from the bottom edge
        (s0 - b0, b0), (d1 + b0, b0), (a1, a1 - d1), (a1, s1 - a1),
        (s1 - b1, b1), (d0 + b1, b1), (a0, a0 - d0), (a0, s0 - a0))], axis=1)  # (C, 8, 2)
    nxt = np.roll(corners, -1, axis=1)
    area = 0.5 * np.abs((corners[..., 0] * nxt[..., 1] - nxt[..., 0] * corners[..., 1]).sum(axis=1))
    centroid = records["position"][:, :3].astype(np.float64)
    base = centroid - sum(np.einsum("ij,ij->i", centroid, t)[:, None] * t for t in (t1, t2))  # the plane's foot
    out = np.zeros((count, 8, 4), np.float32)
    out[..., :3] = base[:, None] + corners[..., :1] * t1[:, None] + corners[..., 1:] * t2[:, None]
    planar = np.linalg.norm(mean_normal, axis=1) >= PLANAR  # not axis_plane: a cap's mean normal can be an axis
    out[:, 0, 3] = planar & (area > 1e-6 * cell * cell)
    out[:, 1, 3] = area
    return out


def box_distance(points: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Distance from each point (N, 3) to each box (N, 2, 3) (0 inside)."""
    return np.linalg.norm(np.maximum(box[:, 0] - points, 0) + np.maximum(points - box[:, 1], 0), axis=1)


def own_side(clusters: Clusters, cells: np.ndarray, normals: np.ndarray, pos: np.ndarray,
             normal: np.ndarray, axis: np.ndarray | None = None) -> np.ndarray:
    """Per record (positions `pos`, unit `normal`): the cluster of the side facing its way of the surface voxel it
    lies in (`cells` (R, 3) and mean `normals` (R, 3): the receivers clusters.side_cluster numbers; with `axis`
    (R,), receivers per dominant axis (lpv/receivers.py), the one of the record's own axis); −2 where that side
    has none (it faces nothing: the record's light leaves the scene); −1 where the record's voxel holds no surface,
    or where that side's mean normal lies more than 60° from the record's (OWN_ALIGN): the side is mostly other
    surfaces — at a room's edge a voxel holds the ceiling's inside and the wall's outside on one side, and the
    sunlit outside's light would light the room. (Two walls at a 90° junction lie 45° from their mean, three 55°.)"""
    out = np.full(len(pos), -1, np.int64)
    if len(cells) == 0:
        return out
    nx, ny, nz = (int(n) for n in clusters.fine.size)
    mine = np.zeros(len(cells), np.int64) if axis is None else np.asarray(axis, np.int64)
    lin = ((cells[:, 2].astype(np.int64) * ny + cells[:, 1]) * nx + cells[:, 0]) * 3 + mine
    order = np.argsort(lin)
    f = np.floor((pos - np.asarray(clusters.fine.origin)) / clusters.fine.cell).astype(np.int64)
    theirs = 0 if axis is None else np.argmax(np.abs(normal), axis=1)
    want = ((f[:, 2] * ny + f[:, 1]) * nx + f[:, 0]) * 3 + theirs
    r = order[np.minimum(np.searchsorted(lin[order], want), len(lin) - 1)]
    length = np.linalg.norm(normals[r], axis=1)
    facing = np.einsum("ij,ij->i", normals[r], normal) / np.maximum(length, 1e-30)
    hit = np.all((f >= 0) & (f < (nx, ny, nz)), axis=1) & (lin[r] == want) & (length > 0)
    hit &= np.abs(facing) >= OWN_ALIGN
    c = clusters.side_cluster[r, (facing < 0).astype(np.int64)]
    out[hit] = np.where(c[hit] >= 0, c[hit], -2)
    return out


def _block_cluster(clusters: Clusters, pos: np.ndarray, normal: np.ndarray, first: np.ndarray, last: np.ndarray,
                   near: float) -> np.ndarray:
    """Per record: the cluster among clusters.key[first:last] (its block and side) within `near` of it whose plane
    lies nearest, or −1 where none is that near."""
    target = np.full(len(pos), -1)
    offset = np.einsum("ij,ij->i", normal, pos)
    best = np.full(len(pos), np.inf)
    for j in range(int((last - first).max(initial=0))):  # candidates of one key: usually one, a few planes at most
        c = np.minimum(first + j, clusters.count - 1)
        lo, hi = clusters.offsets[c, 0], clusters.offsets[c, 1]
        plane = np.maximum(lo - offset, 0) + np.maximum(offset - hi, 0)
        d = np.where((first + j < last) & (box_distance(pos, clusters.box[c]) <= near), plane, np.inf)
        better = d < best
        target[better], best[better] = c[better], d[better]
    return target


def bin_flux(clusters: Clusters, records: np.ndarray, cells: np.ndarray | None = None,
             normals: np.ndarray | None = None, groups: int | None = None,
             axis: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | float]:
    """The VPL records' flux (RGB) per cluster. With the clusters' voxels (`cells`, `normals`), a record goes to
    the cluster of its own voxel's side that faces its way (own_side), or leaves the scene where that side faces
    nothing: a record on the outside of a room's wall is not the inside's, however near a cluster of the room that
    faces its way lies (a sofa's back inside the wall, a corner voxel that also holds the ceiling's inside: in the
    window room, lit by its sun alone, 5 W of the 9 W binned came from the sunlit outside). A record whose voxel
    holds no surface (or any record, without `cells`: the unit tests of the fallback) goes to a cluster of its
    block and side within a voxel of it, the one whose plane lies nearest; else
    (a texel in a voxel that the geometry around it claims for another side: a floor's edge at a wall) to the
    nearest cluster facing its way. A record that faces nothing (a sunlit roof's top) leaves the scene, whatever
    voxel side it shares with other surfaces. Returns ((C, 3), the flux that leaves); with `groups` (G, an int),
    binned apart by the records' group (their flux.w: the light, lpv/gather.rsm_records): ((G, C, 3), (G, 3)
    leaving)."""
    out = np.zeros((clusters.count, 3))
    if len(records) == 0:
        return (out, 0.0) if groups is None else (np.zeros((groups, clusters.count, 3)), np.zeros((groups, 3)))
    pos, normal = records["position"][:, :3].astype(np.float64), records["normal"][:, :3].astype(np.float64)
    flux = records["flux"][:, :3].astype(np.float64)
    near = clusters.fine.cell
    key = block_keys(pos, normal, clusters.fine, clusters.block)
    first = np.searchsorted(clusters.key, key, "left")
    last = np.searchsorted(clusters.key, key, "right")
    faces = faces_something(pos, normal, clusters.lo, clusters.hi, near)
    own = np.full(len(records), -1) if cells is None else own_side(clusters, cells, normals, pos, normal, axis)
    own[~faces] = -2  # nothing lies before it (a roof's top): its light leaves, whichever voxel side it shares
    target = np.where(own >= 0, own, -1)
    alone = np.nonzero(own == -1)[0]  # records with a voxel of their own take no other: the rest search their block
    target[alone] = _block_cluster(clusters, pos[alone], normal[alone], first[alone], last[alone], near)
    lost = np.nonzero((target < 0) & (own == -1))[0]
    for chunk in np.array_split(lost, max(1, len(lost) // 256)) if len(lost) and clusters.count else ():
        facing = normal[chunk] @ clusters.records["normal"][:, :3].T > 0.5  # (n, C)
        gap = np.maximum(clusters.box[None, :, 0] - pos[chunk, None], 0) + \
            np.maximum(pos[chunk, None] - clusters.box[None, :, 1], 0)
        d = np.where(facing, np.linalg.norm(gap, axis=2), np.inf)
        target[chunk] = np.where(np.isfinite(d.min(axis=1)), np.argmin(d, axis=1), -1)
    keep = target >= 0
    if groups is not None:
        g = records["flux"][:, 3].astype(np.int64)
        slot = g[keep] * clusters.count + target[keep]
        binned = np.stack([np.bincount(slot, flux[keep, i], groups * clusters.count) for i in range(3)], axis=1)
        lost = np.stack([np.bincount(g[~keep], flux[~keep, i], groups) for i in range(3)], axis=1).astype(np.float64)
        return binned.reshape(groups, clusters.count, 3), lost
    for i in range(3):
        out[:, i] = np.bincount(target[keep], flux[keep, i], clusters.count)
    return out, float(flux[~keep].sum())
