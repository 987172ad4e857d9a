# SPDX-License-Identifier: GPL-3.0-or-later
"""A receiver cut by a wall in its own voxel (lpv/receivers.py): kept on the side the wall faces.

A receiver is one voxel's surfaces of one dominant axis, placed at their centroid. Where a wall stands on a floor
that goes on under it — a building on a ground plane, a box on a floor, the default cube on its plane, and the box's
own bottom face lying on the floor — the voxel at the wall's foot holds floor on both sides of the wall, and its
receiver's centroid lies on the wall's plane: the wall's clusters light nothing in their own plane (lpv/gather.glsl
OWN_PLANE), so that receiver got almost none of the wall's light, and the pixels of the floor in front of the wall
read it. With voxels of 3.4 m (a town block 200 m across at 32³) the ground in front of a sunlit façade got 0.54 of
Cycles' Diffuse Indirect and the façade's lowest metre 0.53 (its ground was that receiver's light).

The voxelisation knows which way a voxel's surfaces face (voxel/common.glsl: normal w, the facing); a wall whose
surfaces all face one way has its room, or the open air, in front of it. The floor behind such a wall, within the
wall's own extent, is dropped from the receiver: its centroid, box and area become those of the part in front (the
part a pixel in front of the wall stands on). The part behind is the inside of a closed box, or the far side of a
one-sided wall; a wall with both faces in the voxel (a slab) faces both ways and cuts nothing, nor does a wall
whose floor ends at it (a room's), or one whose floor covers no more of the voxel than lies in front of it (a
floor cut by a wall at an angle). The part is found on a SAMPLES × SAMPLES grid over the receiver's box, in its
plane, taken as covered throughout.

Left as it was: a single quad standing free on a floor (a partition one face thick) faces one way, but the floor
behind it is a room too; its voxel's floor now reads the front side's light."""
from __future__ import annotations

import numpy as np

SAMPLES = 16  # per side of the receiver's box
ONE_SIDED = 0.9  # |facing| of a wall whose surfaces face one way
PLANAR = 0.9  # |mean normal| of a receiver or wall whose surfaces lie in one plane
ACROSS = 0.5  # |n_wall · n_receiver| below which the wall stands across the receiver's plane
SLIVER = 0.02  # a part kept or dropped smaller than this share of the box leaves the receiver as it was
FILLED = 0.1  # surfaces covering this much more of the box than lies in front of the wall reach behind it


def clip_to_walls(r: dict, cell: float) -> dict:
    """`r` (lpv/receivers._receivers' dict: cells, axis, normals, areas, positions, lo, hi, facing; receivers
    sorted by voxel, then axis) with every receiver cut by a one-sided wall of its own voxel kept in front of the
    wall: positions, lo, hi and areas replaced (new arrays; `r` itself where no wall cuts one); `cell`: the fine
    voxel's size (m)."""
    cells, normals = r["cells"], r["normals"]
    count = len(cells)
    length = np.linalg.norm(normals, axis=1)
    wall = (np.abs(r["facing"]) >= ONE_SIDED) & (length >= PLANAR)
    if count == 0 or not wall.any():
        return r
    facing_unit = normals / np.maximum(length, 1e-30)[:, None] * np.sign(r["facing"])[:, None]
    same = lambda a, b: np.all(cells[a] == cells[b], axis=1)  # noqa: E731 (receivers a, b share a voxel)
    pairs = []
    for offset in (-2, -1, 1, 2):  # a voxel has at most three receivers, one per axis, in a row
        a = np.arange(max(0, -offset), min(count, count - offset))
        b = a + offset
        keep = same(a, b) & wall[b] & (length[a] >= PLANAR)
        keep &= np.abs(np.einsum("ij,ij->i", facing_unit[b], normals[a] / np.maximum(length[a], 1e-30)[:, None])) \
            <= ACROSS
        pairs.append(np.stack([a[keep], b[keep]], axis=1))
    pairs = np.concatenate(pairs)
    # only where the wall's plane cuts the receiver's box: neither all of it in front of the wall nor all of it
    # behind (the two faces of a box at its edge: each lies behind the other), the region behind being convex
    corners = np.stack(np.meshgrid(*([[0, 1]] * 3), indexing="ij"), axis=-1).reshape(8, 3)
    rec = pairs[:, 0]
    box = r["lo"][rec][:, None] + corners[None] * (r["hi"][rec] - r["lo"][rec])[:, None]  # (P, 8, 3)
    margin = cell / SAMPLES  # a sample's width: a floor that ends at the wall is not cut by it
    deep = _behind(r, facing_unit, pairs[:, 1], box, cell, margin).any(axis=1)
    pairs = pairs[deep & ~_behind(r, facing_unit, pairs[:, 1], box, cell, -margin).all(axis=1)]
    if len(pairs) == 0:
        return r
    pairs = pairs[np.argsort(pairs[:, 0], kind="stable")]
    cut, first = np.unique(pairs[:, 0], return_index=True)
    points = _box_samples(r, cut)  # (N, S², 3)
    q = points[np.searchsorted(cut, pairs[:, 0])]  # (P, S², 3): each pair's receiver's samples
    behind = np.logical_or.reduceat(_behind(r, facing_unit, pairs[:, 1], q, cell), first, axis=0)  # any wall's
    share = 1.0 - behind.mean(axis=1)
    fill = _fill(r, cut)
    # Only where the surfaces reach behind the wall: more of the box is covered than lies in front of it (a floor
    # cut by a wall at an angle, inside a turned room, covers just the part in front of its wall).
    change = (share >= SLIVER) & (share <= 1.0 - SLIVER) & (fill > share + FILLED)
    out = {k: np.array(r[k], copy=True) for k in ("positions", "lo", "hi", "areas")}
    i, kept, q = cut[change], ~behind[change], points[change]
    n = kept.sum(axis=1)[:, None]
    out["positions"][i] = (q * kept[..., None]).sum(axis=1) / n
    half = 0.5 * (r["hi"][i] - r["lo"][i]) / SAMPLES  # a sample stands for its square of the box
    own = np.arange(3)[None, :] == r["axis"][i][:, None]  # the receiver's own axis keeps its extent
    low = np.maximum(np.where(kept[..., None], q, np.inf).min(axis=1) - half, r["lo"][i])
    high = np.minimum(np.where(kept[..., None], q, -np.inf).max(axis=1) + half, r["hi"][i])
    out["lo"][i] = np.where(own, r["lo"][i], low)
    out["hi"][i] = np.where(own, r["hi"][i], high)
    out["areas"][i] = r["areas"][i] * np.minimum(1.0, share[change] / fill[change])  # the front part, covered
    return {**r, **out}


def _fill(r: dict, which: np.ndarray) -> np.ndarray:
    """(N,): the share of receivers `which`'s boxes that their surfaces cover, in their own plane (1 for a floor
    that runs through the voxel; receivers' areas are at most one layer's, lpv/occlusion.layer_area)."""
    a = r["axis"][which].astype(np.int64)
    span = np.asarray(r["hi"], np.float64)[which] - np.asarray(r["lo"], np.float64)[which]
    rows = np.arange(len(which))
    n = np.asarray(r["normals"], np.float64)[which]
    lean = np.abs(n[rows, a]) / np.maximum(np.linalg.norm(n, axis=1), 1e-30)
    section = span[rows, (a + 1) % 3] * span[rows, (a + 2) % 3]
    return np.asarray(r["areas"], np.float64)[which] * lean / np.maximum(section, 1e-30)


def _behind(r: dict, facing_unit: np.ndarray, walls: np.ndarray, q: np.ndarray, cell: float,
            margin: float = 0.0) -> np.ndarray:
    """(P, K) bool: whether points q (P, K, 3) lie behind wall receiver walls[p] — behind its plane by more than
    `margin`, and within its own extent along the axes of its plane (a wall that ends in the voxel cuts no
    further)."""
    back = np.einsum("pkj,pj->pk", q - r["positions"][walls][:, None], facing_unit[walls]) < -margin
    tolerance = cell * (0.5 / SAMPLES + 0.02)
    plane = np.arange(3)[None, :] != r["axis"][walls][:, None]  # (P, 3)
    beyond = (q < r["lo"][walls][:, None] - tolerance) | (q > r["hi"][walls][:, None] + tolerance)
    return back & ~np.any(beyond & plane[:, None, :], axis=2)


def _box_samples(r: dict, which: np.ndarray) -> np.ndarray:
    """(N, SAMPLES², 3): points on a grid over receivers `which`'s boxes, along the two axes of their plane, lifted
    onto the plane through their centroid across their mean normal."""
    t = (np.arange(SAMPLES) + 0.5) / SAMPLES
    u, v = (g.reshape(1, -1) for g in np.meshgrid(t, t, indexing="ij"))
    a = r["axis"][which].astype(np.int64)[:, None]
    b, c = (a + 1) % 3, (a + 2) % 3
    lo, hi, p, n = (np.asarray(r[k], np.float64)[which] for k in ("lo", "hi", "positions", "normals"))
    pick = lambda x, k: np.take_along_axis(x, k, axis=1)  # noqa: E731 (column k of each row)
    along_b = pick(lo, b) + u * pick(hi - lo, b)  # (N, S²)
    along_c = pick(lo, c) + v * pick(hi - lo, c)
    along_a = pick(p, a) - (pick(n, b) * (along_b - pick(p, b)) + pick(n, c) * (along_c - pick(p, c))) / pick(n, a)
    eye = np.eye(3)
    return sum(eye[k[:, 0]][:, None, :] * x[..., None] for k, x in ((a, along_a), (b, along_b), (c, along_c)))
