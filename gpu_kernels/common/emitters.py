# SPDX-License-Identifier: GPL-3.0-or-later
"""Emissive triangles → a bounded number of shadowed emitter clusters (pure numpy; issue 17).

Every emissive triangle is lit exactly (Lambert's formula per triangle, shaders/common/light_eval.glsl), and every
one is shadowed: triangles are grouped into at most `max_clusters` clusters of neighbouring, similarly oriented
triangles, and each cluster gets its own shadow sample points, like an area light's (common/lights.py). A cluster is
one polygon light whose polygon is a list of triangles, each with its own radiance, so a cluster may span materials.

Clustering is top-down, over features (centroid / L, 2·axis(normal)) weighted by each triangle's emitted power
(area × mean radiance): L = sqrt(total emissive area / π) makes it independent of the scene's scale, and
axis(n) = the upper triangle of n·nᵀ (|axis(a) − axis(b)|² = 2 sin²θ) ignores the sign of a normal, as two-sided
emission does. A cluster is split in two at its weighted mean along the principal direction of its features.
First every cluster that is not flat (a normal more than FLAT_DEGREES from its axis, or thicker along that axis than
tan(FLAT_DEGREES) × its diameter — a shade's two caps, opposite walls) is split, the largest scatter first, until all
are flat or there are max_clusters; then any, the largest scatter first, until there are max_clusters / 4: flat
clusters are better served by more sample points than by more clusters.

Each cluster side gets 1 … MAX_SAMPLES_PER_SIDE sample points (the spare budget by emitted power; twice as many
on the one side of a closed shell), each
at the centre of a k-means cell of the cluster's area, snapped onto the surface (a curved cluster's mean point lies
inside it), with the normal of the triangle it lies on and the share of the cluster's area it stands for. Both sides
of the surface get a sample there (emission is two-sided, as in Cycles; a closed shell's inner side none, see
below), nudged off it by 1e-3 of the triangle's size so the surface does not shadow its own sample.

Trapped light. A closed emissive surface (every edge of a connected set of emissive triangles shared by an even
number of them) — a closed lamp shade, with or without a bulb or the end of the lamp's pole inside — emits half its
light inwards, and that light can only ever light the inside, which no camera outside sees (a shell around the
camera, like the white furnace's box or an emissive dome around the scene, traps nothing). So such a shell emits
outwards only: its triangles are wound outwards (common/shells.outward) and marked one-sided, and its inner samples,
marked `trapped`, get no shadow cube (common/lights.py), so they take no part in any pass.
Lit two-sided, the receivers outside got the inner sides of the far triangles in their exact integral, and the
samples' weights had to take that share out again, which they do only roughly (a floor under a shade: rel-L1 0.005
against the exact integral, below 0.0001 one-sided, tests/gpu/test_emitters.py); the cubes the inner side no longer
needs go to more points on the outer side (samples_per_side). And the voxels would let the inner light
out: a thin shell is not opaque at VCT's coarse mip levels nor in the LPV's fuzzy occlusion (in
tests/support/emitter_scenes.lamp_room_albedo, with the inner light kept, Diffuse Indirect was 2.9× Cycles' with VCT
and 1.5× with the LPV). Inside and outside are told apart by the parity of ray crossings (three rays, the majority
wins).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .shells import inside_closed, mesh_components, outward

MAX_SAMPLES_PER_SIDE = 4  # penumbra sample points per cluster side (an area light has 2×2 by default)
NORMAL_WEIGHT = 2.0  # weight of axis(normal) against centroid / L in the clustering features (module docstring)
FLAT_DEGREES = 15.0  # a cluster is flat when all its normals are within this of its axis (sign-free)
NUDGE = 1e-3  # sample points sit this fraction of their triangle's size off the surface
KMEANS_ITERATIONS = 8


@dataclass
class EmitterCluster:
    """Emissive triangles lit as one polygon light, shadowed from its own sample points."""
    triangles: np.ndarray  # (T,) indices into Scene.positions
    vertices: np.ndarray  # (T, 3, 3) world positions
    radiance: np.ndarray  # (T, 3) emitted radiance of each triangle
    normal: np.ndarray  # (3,) unit mean orientation (sign arbitrary: emission is two-sided)
    centroid: np.ndarray  # (3,) area-weighted
    area: float
    sample_points: np.ndarray  # (S, 3) on the surface; each gives two shadow samples, one per side
    sample_normals: np.ndarray  # (S, 3) unit normal of the triangle each lies on
    sample_areas: np.ndarray  # (S,) the share of `area` each stands for (sums to area)
    sample_sizes: np.ndarray  # (S,) sqrt of the area of the triangle each lies on (the nudge's scale)
    sample_trapped: np.ndarray = None  # (S, 2) bool: the side (+n, −n) faces the sealed inside of a closed emitter
    sample_component: np.ndarray = None  # (S,) the trapping shell each sample lies on (−1: none)
    one_sided: np.ndarray = None  # (T,) emits along its winding normal only (a trapping shell's, wound outwards)


def emissive_triangles(scene) -> tuple[np.ndarray, np.ndarray]:
    """Indices of triangles whose material emits (zero-area ones left out), and their emitted radiance (RGB)."""
    if scene.triangle_count == 0 or not scene.materials:
        return np.zeros(0, np.int64), np.zeros((0, 3))
    emission = np.array([m.emission for m in scene.materials], np.float64).reshape(-1, 3)
    mat = np.clip(scene.material_index, 0, len(scene.materials) - 1)
    idx = np.nonzero(emission[mat].max(axis=1) > 0)[0]
    if len(idx) == 0:
        return idx, np.zeros((0, 3))
    p = scene.positions[idx].astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    keep = area > 0
    return idx[keep], emission[mat[idx[keep]]]


def _axis(n: np.ndarray) -> np.ndarray:
    """(N, 6) sign-free embedding of unit normals: |axis(a) − axis(b)|² = 2(1 − (a·b)²)."""
    r2 = math.sqrt(2.0)
    return np.stack([n[:, 0] ** 2, n[:, 1] ** 2, n[:, 2] ** 2, r2 * n[:, 0] * n[:, 1], r2 * n[:, 0] * n[:, 2],
                     r2 * n[:, 1] * n[:, 2]], axis=1)


def _scatter(f: np.ndarray, w: np.ndarray) -> float:
    mean = (w[:, None] * f).sum(axis=0) / w.sum()
    return float((w * ((f - mean) ** 2).sum(axis=1)).sum())


def _split(f: np.ndarray, w: np.ndarray, members: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two halves of `members` at the weighted mean along the principal direction of their features."""
    fm, wm = f[members], w[members]
    mean = (wm[:, None] * fm).sum(axis=0) / wm.sum()
    d = fm - mean
    cov = (wm[:, None] * d).T @ d
    _, vecs = np.linalg.eigh(cov)
    t = d @ vecs[:, -1]
    left = t < 0
    if left.all() or not left.any():  # identical features (duplicated triangles): split the list in half
        left = np.arange(len(members)) < len(members) // 2
    return members[left], members[~left]


def _flat(tri: np.ndarray, normal: np.ndarray, w: np.ndarray) -> bool:
    """Whether triangles form one nearly flat sheet: every normal within FLAT_DEGREES of the weighted principal axis
    (sign-free), and the sheet no thicker along that axis than tan(FLAT_DEGREES) × its diameter (which keeps
    parallel faces apart: a shade's two caps, the opposite walls of a cylinder)."""
    _, vecs = np.linalg.eigh((w[:, None] * normal).T @ normal)
    axis = vecs[:, -1]
    limit = math.radians(FLAT_DEGREES)
    if np.abs(normal @ axis).min() < math.cos(limit):
        return False
    v = tri.reshape(-1, 3)
    height = v @ axis
    return bool(height.max() - height.min() <= math.tan(limit) * np.linalg.norm(v.max(0) - v.min(0)))


def cluster_triangles(positions: np.ndarray, max_clusters: int, min_clusters: int = 1,
                      weights: np.ndarray | None = None) -> list[np.ndarray]:
    """Top-down clustering of triangles (T, 3, 3) into lists of indices (module docstring): first the clusters
    that are not flat (a normal more than FLAT_DEGREES from the cluster's axis) are split, the largest scatter first,
    until all are flat or there are max_clusters; then any, until there are min_clusters. `weights`: each
    triangle's share of the emitted power (default: its area)."""
    tri = np.asarray(positions, np.float64)
    count = len(tri)
    if count == 0:
        return []
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    normal = cross / np.maximum(2 * area, 1e-300)[:, None]
    scale = math.sqrt(area.sum() / math.pi)
    f = np.concatenate([tri.mean(axis=1) / scale, NORMAL_WEIGHT * _axis(normal)], axis=1)
    w = area if weights is None else np.asarray(weights, np.float64)
    w = w / w.sum() if w.sum() > 0 else np.full(count, 1.0 / count)

    def entry(members):  # (scatter, flat, members)
        return (_scatter(f[members], w[members]) if len(members) > 1 else -1.0,
                len(members) == 1 or _flat(tri[members], normal[members], w[members]), members)

    clusters = [entry(np.arange(count))]
    for phase in (0, 1):
        limit = max_clusters if phase == 0 else min(max_clusters, min_clusters)
        while len(clusters) < max(1, limit):
            open_ = [k for k, (sc, flat, m) in enumerate(clusters) if len(m) > 1 and (phase == 1 or not flat)]
            if not open_:
                break
            k = max(open_, key=lambda k: clusters[k][0])
            clusters.extend(entry(half) for half in _split(f, w, clusters.pop(k)[2]))
    return sorted([m for _, _, m in clusters], key=lambda m: int(m.min()))


def _candidates(tri: np.ndarray, wanted: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points spread over the triangles (centroids of their midpoint subdivisions, ≥ `wanted` in all where it
    takes ≤ 3 subdivisions), the area each stands for and the index of its triangle."""
    level = 0
    while len(tri) * 4 ** level < wanted and level < 3:
        level += 1
    sub = tri[:, None]  # (T, 1, 3, 3)
    for _ in range(level):
        a, b, c = sub[..., 0, :], sub[..., 1, :], sub[..., 2, :]
        ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
        sub = np.stack([np.stack(s, axis=-2) for s in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))],
                       axis=2).reshape(len(tri), -1, 3, 3)
    per = sub.shape[1]
    points = sub.mean(axis=2).reshape(-1, 3)
    areas = 0.5 * np.linalg.norm(np.cross(sub[..., 1, :] - sub[..., 0, :], sub[..., 2, :] - sub[..., 0, :]),
                                 axis=-1).reshape(-1)
    return points, areas, np.repeat(np.arange(len(tri)), per)


def sample_points(tri: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`count` sample points on triangles (T, 3, 3): (points on the surface, the index of the triangle each lies on,
    the area each stands for). Weighted k-means over candidate points (farthest-point start, deterministic); each
    centre is snapped to its nearest candidate, which lies on the surface."""
    points, areas, owner = _candidates(tri, 8 * count)
    count = min(count, len(points))
    centres = [int(np.argmin(((points - (areas[:, None] * points).sum(0) / areas.sum()) ** 2).sum(1)))]
    dist = ((points - points[centres[0]]) ** 2).sum(1)
    while len(centres) < count:
        centres.append(int(np.argmax(dist * areas)))
        dist = np.minimum(dist, ((points - points[centres[-1]]) ** 2).sum(1))
    c = points[centres]
    for _ in range(KMEANS_ITERATIONS if count > 1 else 0):
        label = np.argmin(((points[:, None] - c[None]) ** 2).sum(-1), axis=1)
        for k in range(count):
            m = label == k
            if m.any():
                c[k] = (areas[m, None] * points[m]).sum(0) / areas[m].sum()
    label = np.argmin(((points[:, None] - c[None]) ** 2).sum(-1), axis=1) if count > 1 else np.zeros(len(points), int)
    snapped, share = [], []
    for k in range(count):
        m = np.nonzero(label == k)[0]
        if len(m) == 0:
            continue
        snapped.append(m[np.argmin(((points[m] - c[k]) ** 2).sum(1))])
        share.append(areas[m].sum())
    snapped = np.array(snapped)
    return points[snapped], owner[snapped], np.array(share)


def samples_per_side(areas: np.ndarray, budget: int, one_sided: np.ndarray | None = None) -> np.ndarray:
    """Sample points per side for clusters of these powers (or areas): one each, then the spare budget (in sample
    points on both sides) by largest remainder of the share, at most MAX_SAMPLES_PER_SIDE on each side. A
    `one_sided` cluster (a closed shell's: its inner side gets no cube) pays half for a point and may have twice as
    many: the same shadow cubes."""
    cost = np.where(np.zeros(len(areas), bool) if one_sided is None else one_sided, 0.5, 1.0)
    cap = MAX_SAMPLES_PER_SIDE / cost
    n = np.ones(len(areas), np.int64)
    spare = budget - cost.sum()
    while True:
        open_ = (n < cap) & (cost <= spare + 1e-9)
        if not open_.any():
            return n
        units = areas / areas[open_].sum() * (spare + (n * cost)[open_].sum())  # each one's share of the budget
        k = int(np.argmax(np.where(open_, units / cost - n, -np.inf)))
        n[k] += 1
        spare -= cost[k]


def cluster_emitters(scene, max_clusters: int, samples_budget: int,
                     trapping: list | None = None) -> list[EmitterCluster]:
    """Every emissive triangle of `scene` in ≤ max_clusters clusters, with ≤ samples_budget sample points per side
    in all (≥ 1 per cluster). `trapping`: the closed emitters (arrays of triangle indices) whose inside traps their
    light (default trapping_shells(scene)); the samples facing their inside are marked trapped."""
    idx, radiance = emissive_triangles(scene)
    if len(idx) == 0:
        return []
    tri_all = scene.positions[idx].astype(np.float64)
    trapping = trapping_shells(scene) if trapping is None else trapping
    component = np.full(len(idx), -1)
    where = {t: i for i, t in enumerate(idx.tolist())}
    for k, shell in enumerate(trapping):
        component[[where[t] for t in np.asarray(shell).tolist() if t in where]] = k
        # Its triangles emit outwards only (see the module docstring): wound so that their normals point out.
        tri_all[component == k] = outward(tri_all[component == k])
    power = _areas(tri_all) * radiance.mean(axis=1)
    cap = min(max_clusters, samples_budget)
    groups = cluster_triangles(tri_all, cap, max(1, cap // 4), power)
    per_side = samples_per_side(np.array([power[g].sum() for g in groups]), samples_budget,
                                np.array([bool((component[g] >= 0).all()) for g in groups]))
    out = []
    for g, n_samples in zip(groups, per_side):
        tri = tri_all[g]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        a = 0.5 * np.linalg.norm(cross, axis=1)
        unit = cross / (2 * a)[:, None]
        # The mean orientation: the principal axis of Σ a·n·nᵀ (sign-free), signed towards most of the area.
        _, vecs = np.linalg.eigh((a[:, None] * unit).T @ unit)
        normal = vecs[:, -1] * (1.0 if (a * (unit @ vecs[:, -1])).sum() >= 0 else -1.0)
        pts, owner, share = sample_points(tri, int(n_samples))
        c = EmitterCluster(idx[g], tri, radiance[g], normal, (a[:, None] * tri.mean(axis=1)).sum(0) / a.sum(),
                           float(a.sum()), pts, unit[owner], share, np.sqrt(a[owner]))
        c.sample_trapped = np.zeros((len(pts), 2), bool)
        c.one_sided = component[g] >= 0
        c.sample_component = component[g[owner]]
        out.append(c)
    for comp in range(len(trapping)):  # every sample on a trapping shell: which of its two sides faces the inside
        which = [(c, k) for c in out for k in np.nonzero(c.sample_component == comp)[0]]
        if not which:
            continue
        points = np.array([side[0] for c, k in which for side in side_samples(c)[2 * k:2 * k + 2]])
        inside = inside_closed(tri_all[component == comp], points).reshape(-1, 2)
        for (c, k), flags in zip(which, inside):
            c.sample_trapped[k] = flags
    return out


def _areas(tri: np.ndarray) -> np.ndarray:
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def side_samples(cluster: EmitterCluster) -> list[tuple[np.ndarray, np.ndarray, float, bool]]:
    """(point, normal it emits along, area it stands for, trapped) of every shadow sample of a cluster: each sample
    point twice, nudged off its triangle along +n and −n (NUDGE of the triangle's size)."""
    out = []
    trapped = cluster.sample_trapped if cluster.sample_trapped is not None else \
        np.zeros((len(cluster.sample_points), 2), bool)
    for p, n, share, size, tr in zip(cluster.sample_points, cluster.sample_normals, cluster.sample_areas,
                                     cluster.sample_sizes, trapped):
        for j, side in enumerate((1.0, -1.0)):
            out.append((p + side * NUDGE * size * n, side * n, float(share), bool(tr[j])))
    return out


# --------------------------------------------------------------------------- closed emitters (trapped light)

def sealed_shells(scene) -> list[np.ndarray]:
    """The closed emissive surfaces of `scene`, as arrays of triangle indices: connected emissive triangles every
    edge of which is shared an even number of times. Whatever lies inside one (a bulb, the end of the lamp's pole)
    is seen only from inside too, so it does not open it; only a camera inside does (shells_around)."""
    idx, _ = emissive_triangles(scene)
    if len(idx) == 0:
        return []
    comp, closed = mesh_components(scene.positions[idx].astype(np.float64))
    return [idx[comp == c] for c in np.nonzero(closed)[0]]


def shells_around(scene, shells: list, point) -> tuple:
    """The indices of `shells` (sealed_shells) that enclose `point` (the camera: their inside is then what it sees,
    and their inner light is not trapped for it)."""
    if point is None:
        return ()
    p = np.asarray(point, np.float64)[None]
    return tuple(k for k, s in enumerate(shells)
                 if inside_closed(scene.positions[s].astype(np.float64), p)[0])


def trapping_shells(scene, shells: list | None = None) -> list[np.ndarray]:
    """The sealed shells whose inner light is trapped: all of them but those around the scene's camera."""
    shells = sealed_shells(scene) if shells is None else shells
    camera = None if scene.camera is None else np.asarray(scene.camera.matrix_world, np.float64)[:3, 3]
    around = shells_around(scene, shells, camera)
    return [s for k, s in enumerate(shells) if k not in around]
