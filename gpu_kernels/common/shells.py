# SPDX-License-Identifier: GPL-3.0-or-later
"""Closed triangle meshes (pure numpy): connected components and whether each is closed, inside / outside by the
parity of ray crossings, and each closed surface's triangles turned to face outwards. common/emitters.py uses them
for the light a closed emitter traps inside itself."""
from __future__ import annotations

import numpy as np

RAY_DIRECTIONS = np.array([[0.5773, 0.6124, 0.5400], [-0.7071, 0.3090, 0.6360], [0.2113, -0.8660, 0.4532]])
RAY_DIRECTIONS /= np.linalg.norm(RAY_DIRECTIONS, axis=1, keepdims=True)
PARITY_CHUNK = 1 << 22  # point × triangle pairs per numpy step


def _vertex_ids(tri: np.ndarray) -> np.ndarray:
    """(T, 3) one id per distinct vertex position (equal bit for bit in float32, as a mesh's shared vertices are
    after extraction)."""
    verts = np.ascontiguousarray(tri.reshape(-1, 3).astype(np.float32))
    _, vid = np.unique(verts.view(np.dtype((np.void, 12))).ravel(), return_inverse=True)
    return vid.reshape(len(tri), 3)


def mesh_components(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Connected components of triangles (T, 3, 3) that share edges (vertices equal bit for bit, as a mesh's
    shared vertices are after extraction), and per component whether it is closed: every edge used an even number
    of times."""
    count = len(tri)
    vid = _vertex_ids(tri)
    edges = np.sort(np.stack([vid[:, [0, 1]], vid[:, [1, 2]], vid[:, [2, 0]]], axis=1), axis=2).reshape(-1, 2)
    owner = np.repeat(np.arange(count), 3)
    key = edges[:, 0].astype(np.int64) * (int(vid.max()) + 1) + edges[:, 1]
    order = np.argsort(key, kind="stable")
    key, owner = key[order], owner[order]
    same = key[1:] == key[:-1]
    _, comp = np.unique(_union_find(count, owner[:-1][same], owner[1:][same]), return_inverse=True)
    starts = np.concatenate([[True], key[1:] != key[:-1]])
    uses = np.diff(np.concatenate([np.nonzero(starts)[0], [len(key)]]))
    odd_edge_owner = owner[np.nonzero(starts)[0][uses % 2 == 1]]
    closed = np.ones(comp.max() + 1, bool)
    closed[comp[odd_edge_owner]] = False
    return comp, closed


def _union_find(count: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Root (smallest member) of each of `count` elements joined by the pairs (a, b): hooking of roots onto the
    smaller root, then full path compression, until no pair spans two roots (a few rounds, vectorised)."""
    parent = np.arange(count)
    while True:
        ra, rb = parent[a], parent[b]
        apart = ra != rb
        if not apart.any():
            return parent
        lo, hi = np.minimum(ra[apart], rb[apart]), np.maximum(ra[apart], rb[apart])
        np.minimum.at(parent, hi, lo)
        while True:
            nxt = parent[parent]
            if np.array_equal(nxt, parent):
                break
            parent = nxt


def _crossings(points: np.ndarray, tri: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Number of triangles the ray points + t·direction (t > 0) crosses, per point (Möller–Trumbore)."""
    out = np.zeros(len(points), np.int64)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    pvec = np.cross(direction, e2)
    det = (e1 * pvec).sum(1)
    ok = np.abs(det) > 1e-30
    e1, e2, v0, pvec, inv = e1[ok], e2[ok], tri[ok, 0], pvec[ok], 1.0 / det[ok]
    step = max(1, PARITY_CHUNK // max(len(v0), 1))
    for s in range(0, len(points), step):
        tvec = points[s:s + step, None] - v0[None]
        u = (tvec * pvec).sum(-1) * inv
        qvec = np.cross(tvec, e1[None])
        v = (qvec * direction).sum(-1) * inv
        t = (qvec * e2[None]).sum(-1) * inv
        out[s:s + step] = ((u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)).sum(1)
    return out


def inside_closed(shell: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Whether each point lies inside the closed surface `shell` (T, 3, 3): odd crossings, majority of three rays."""
    votes = sum((_crossings(points, shell, d) % 2 == 1).astype(int) for d in RAY_DIRECTIONS)
    return votes >= 2


def outward(tri: np.ndarray) -> np.ndarray:
    """The triangles (T, 3, 3) of closed surfaces with two vertices swapped where needed, so that every winding
    normal (b − a) × (c − a) points out of its surface. Windings are made consistent across the edges two triangles
    share (one must run it u → v, the other v → u), then each group of triangles so joined is turned as a whole to
    the sign of its enclosed volume (Σ a · (b × c) > 0 when the normals point out). Edges used other than twice
    join nothing."""
    tri = np.array(tri, np.float64)
    count = len(tri)
    if count == 0:
        return tri
    vid = _vertex_ids(tri)
    a, b = vid.reshape(-1), vid[:, [1, 2, 0]].reshape(-1)  # directed edges, three per triangle
    key = np.minimum(a, b).astype(np.int64) * (int(vid.max()) + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    pairs = np.nonzero(key[order][1:] == key[order][:-1])[0]
    edge = np.unique(key, return_inverse=True)[1]
    uses = np.bincount(edge)[edge]  # how many triangles use each directed edge's undirected edge
    neighbours = [[] for _ in range(count)]
    for i in pairs:
        e1, e2 = order[i], order[i + 1]
        if uses[e1] != 2:
            continue
        same_way = bool((a[e1] < b[e1]) == (a[e2] < b[e2]))  # then one of the two must be flipped
        t1, t2 = e1 // 3, e2 // 3
        neighbours[t1].append((t2, same_way))
        neighbours[t2].append((t1, same_way))
    flip = np.zeros(count, bool)
    group = np.full(count, -1)
    for seed in range(count):
        if group[seed] >= 0:
            continue
        group[seed], stack = seed, [seed]
        while stack:
            t = stack.pop()
            for u, same_way in neighbours[t]:
                if group[u] < 0:
                    group[u], flip[u] = seed, flip[t] ^ same_way
                    stack.append(u)
    tri[flip] = tri[flip][:, [0, 2, 1]]
    volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))
    inward = np.bincount(group, weights=volume, minlength=count) < 0
    turn = inward[group]
    tri[turn] = tri[turn][:, [0, 2, 1]]
    return tri
