"""Synthetic test scenes built from quads, and exact irradiance oracles (shared by the VCT and LPV tests)."""
import math

import numpy as np

from bounce_gi.gpu_kernels import camera as cam
from bounce_gi.gpu_kernels.scene import Camera, Scene, World


def quad(corners, normal):
    """Two triangles of the quad, wound so their geometric normal is `normal`."""
    c = np.asarray(corners, np.float64)
    tris = np.array([[c[0], c[1], c[2]], [c[0], c[2], c[3]]])
    for t in range(2):
        if np.cross(tris[t, 1] - tris[t, 0], tris[t, 2] - tris[t, 0]) @ np.asarray(normal, float) < 0:
            tris[t] = tris[t][::-1]
    return tris


def quad_scene(quads, materials, lights, eye, target, world=(0.0, 0.0, 0.0), lens=16.0):
    """quads: [(triangles (2, 3, 3), material index)]."""
    pos = np.concatenate([q for q, _ in quads]).astype(np.float32)
    n = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    mats = np.concatenate([np.full(len(q), m, np.int32) for q, m in quads])
    c2w = np.linalg.inv(cam.look_at(eye, target, (0, 0, 1)))
    return Scene(pos, np.repeat(n[:, None], 3, axis=1).astype(np.float32), np.zeros((len(pos), 3, 2), np.float32),
                 mats, materials, [], lights, World(world), Camera(c2w, lens=lens))


def box_quads(lo, hi, material, inward=True, skip=()):
    """The six faces of an axis-aligned box, normals pointing in (or out)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    out = []
    for axis in range(3):
        for side, value in (("lo", lo[axis]), ("hi", hi[axis])):
            if (axis, side) in skip:
                continue
            u, w = (axis + 1) % 3, (axis + 2) % 3
            corners = []
            for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = np.zeros(3)
                p[axis], p[u], p[w] = value, (lo[u], hi[u])[a], (lo[w], hi[w])[b]
                corners.append(p)
            normal = np.zeros(3)
            normal[axis] = (1.0 if side == "lo" else -1.0) * (1.0 if inward else -1.0)
            out.append((quad(corners, normal), material))
    return out


def patch_view_factor(points, normals, patch, radiance, m=120):
    """Exact irradiance / π at `points` (normals) from a Lambertian floor rectangle (x0, x1, y0, y1) at z = 0 of
    `radiance`, unoccluded: midpoint rule over m × m cells."""
    x0, x1, y0, y1 = patch
    u = (np.arange(m) + 0.5) / m
    gx, gy = np.meshgrid(x0 + (x1 - x0) * u, y0 + (y1 - y0) * u)
    q = np.stack([gx, gy, np.zeros_like(gx)], -1).reshape(-1, 3)
    out = []
    for p, n in zip(points, normals):
        v = q - p
        r2 = (v * v).sum(-1)
        cos_p, cos_q = np.clip(v @ n, 0, None) / np.sqrt(r2), np.clip(-v[:, 2], 0, None) / np.sqrt(r2)
        out.append(radiance * (cos_p * cos_q / r2).sum() * (x1 - x0) * (y1 - y0) / m ** 2 / math.pi)
    return np.array(out)
