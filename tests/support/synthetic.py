# SPDX-License-Identifier: GPL-3.0-or-later
"""Synthetic test scenes built from quads, and exact irradiance oracles (shared by the VCT and LPV tests)."""
import math

import numpy as np

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.scene import Camera, Light, Material, Scene, World


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


def rectangle_view_factor(points, normals, corner, edge_u, edge_v, m=120):
    """Exact view factors from `points` (normals) to the Lambertian rectangle corner + s·edge_u + t·edge_v, s, t in
    [0, 1], seen from the side its normal edge_u × edge_v faces, unoccluded: midpoint rule over m × m cells."""
    corner, edge_u, edge_v = (np.asarray(a, float) for a in (corner, edge_u, edge_v))
    facing = np.cross(edge_u, edge_v)
    area = float(np.linalg.norm(facing))
    u = (np.arange(m) + 0.5) / m
    s, t = np.meshgrid(u, u)
    q = corner + s.reshape(-1, 1) * edge_u + t.reshape(-1, 1) * edge_v
    out = []
    for p, n in zip(points, normals):
        v = q - p
        r2 = (v * v).sum(-1)
        cos_p, cos_q = np.clip(v @ n, 0, None) / np.sqrt(r2), np.clip(-(v @ facing) / area, 0, None) / np.sqrt(r2)
        out.append((cos_p * cos_q / r2).sum() * area / m ** 2 / math.pi)
    return np.array(out)


def patch_view_factor(points, normals, patch, radiance, m=120):
    """Exact irradiance / π at `points` (normals) from a Lambertian floor rectangle (x0, x1, y0, y1) at z = 0 of
    `radiance`, unoccluded (rectangle_view_factor)."""
    x0, x1, y0, y1 = patch
    return radiance * rectangle_view_factor(points, normals, (x0, y0, 0.0), (x1 - x0, 0.0, 0.0), (0.0, y1 - y0, 0.0), m)


LIT_PATCH = (-1.5, 1.5, -1.25, 1.25)  # x0, x1, y0, y1 of the sunlit patch (albedo 0.7, sun 2 W/m² at 60°)


def lit_patch_scene(receiver: str) -> Scene:
    """A 3 × 2.5 m lit patch in a black 6 × 6 m floor, a grey plate 3 m above it and a grey wall 1.5 m beside it,
    the camera on the plate ("plate above") or the wall ("wall beside"). The sun, 60° from vertical towards +y,
    casts the plate's shadow beyond the floor and gives the wall (normal +x) none: the receivers' indirect light is
    the patch's alone (`lit_patch_error`)."""
    x0, x1, y0, y1 = LIT_PATCH

    def floor(a, b, c, d, m):
        return quad([(a, c, 0), (b, c, 0), (b, d, 0), (a, d, 0)], (0, 0, 1)), m
    quads = [floor(*LIT_PATCH, 1), floor(-3, x0, -3, 3, 0), floor(x1, 3, -3, 3, 0), floor(x0, x1, -3, y0, 0),
             floor(x0, x1, y1, 3, 0),
             (quad([(-1, -1, 3), (1, -1, 3), (1, 1, 3), (-1, 1, 3)], (0, 0, -1)), 2),
             (quad([(-3, -3, 0), (-3, 3, 0), (-3, 3, 3), (-3, -3, 3)], (1, 0, 0)), 2)]
    mats = [Material("black", (0.0,) * 3), Material("patch", (0.7,) * 3), Material("grey", (0.5,) * 3)]
    sun = Light("sun", "SUN", (1, 1, 1), 2.0, np.linalg.inv(cam.look_at((0, -math.sqrt(3), 1), (0, 0, 0), (1, 0, 0))))
    eye, target = ((0.0, -1.9, 1.0), (0.0, 0.0, 3.0)) if receiver == "plate above" else ((2.5, 0, 1.5), (-3, 0, 1.3))
    return quad_scene(quads, mats, [sun], eye, target)


def lit_patch_error(passes) -> tuple[float, float, int]:
    """(mean ours / exact, rel-L1 against exact, pixels) of a render of `lit_patch_scene`'s Diffuse Indirect,
    over every third receiver pixel (the patch's radiance: 0.7 × 2 W/m² × cos 60° / π)."""
    pos, nrm, di = passes["Position"], passes["Normal"], passes["Diffuse Indirect"][..., 0]
    ys, xs = np.nonzero((passes["Depth"][..., 0] < 1e9) & (pos[..., 2] > 1e-3))
    ys, xs = ys[::3], xs[::3]
    exact = patch_view_factor(pos[ys, xs, :3].astype(np.float64), nrm[ys, xs, :3].astype(np.float64), LIT_PATCH,
                              0.7 * 2.0 * 0.5 / math.pi)
    ours = di[ys, xs]
    return float(ours.sum() / exact.sum()), float(np.abs(ours - exact).sum() / exact.sum()), len(ys)


def closed_cylinder(segments=24, radius=0.22, height=0.32, centre=(0.0, 0.0, 1.5), caps=True):
    """A capped cylinder as a mesh's triangles, shared vertices equal bit for bit, every normal pointing out;
    24 segments: 48 side triangles + two 22-triangle caps = 92 (the lamp shade of issue 17)."""
    c = np.asarray(centre, np.float64)
    t = np.arange(segments) * 2 * math.pi / segments
    lo, hi = (np.stack([radius * np.cos(t), radius * np.sin(t), np.full(segments, z)], 1) + c
              for z in (-height / 2, height / 2))
    tris = []
    for i in range(segments):
        j = (i + 1) % segments
        tris += [[lo[i], lo[j], hi[j]], [lo[i], hi[j], hi[i]]]
    if caps:
        for i in range(1, segments - 1):
            tris += [[lo[0], lo[i + 1], lo[i]], [hi[0], hi[i], hi[i + 1]]]
    return np.array(tris, np.float32)


def triangle_projected_solid_angles(points, normals, tris):
    """(P, T) exact ∫ cosθ dω of each triangle (T, 3, 3) seen from each point, for triangles wholly above the
    points' planes (Lambert's formula: ½ |Σ_edges angle(a, b) · n·normalize(a × b)|)."""
    p = np.asarray(points, np.float64)[:, None, None, :]
    v = np.asarray(tris, np.float64)[None] - p  # (P, T, 3, 3)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    n = np.asarray(normals, np.float64)[:, None, :]
    total = 0.0
    for i in range(3):
        a, b = v[:, :, i], v[:, :, (i + 1) % 3]
        c = np.cross(a, b)
        s = np.linalg.norm(c, axis=-1)
        total = total + np.arctan2(s, (a * b).sum(-1)) * (n * c).sum(-1) / np.maximum(s, 1e-300)
    return 0.5 * np.abs(total)


def sphere_scene(subdivisions=3, radius=1.0, albedo=0.5, power=100.0, eye=(0.0, 0.0, 0.0)):
    """A closed icosphere of `radius` and `albedo`, faces inward, a point light of `power` W at its centre, the
    camera at `eye` looking along +x."""
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    pos = m.vertices[m.faces][:, ::-1].astype(np.float32)  # reversed winding: faces point inward
    nrm = (-pos / radius).astype(np.float32)
    cam_to_world = np.linalg.inv(cam.look_at(eye, np.asarray(eye) + (1, 0, 0), (0, 0, 1)))
    return Scene(pos, nrm, np.zeros((len(pos), 3, 2), np.float32), np.zeros(len(pos), np.int32),
                 [Material("wall", (albedo,) * 3)], [], [Light("bulb", "POINT", (1, 1, 1), power, np.eye(4))],
                 World(), Camera(cam_to_world, lens=18.0))


def room_with_box(z, size=0.3, height=None, turn=0.0):
    """A 2 × 2 × 2 m room without a ceiling, lit by a point light, with a `size` m box (`height` m tall: `size`
    where None) standing `z` m above the floor by the wall, turned `turn` degrees about the vertical (the LPV's
    object-move tests)."""
    height = size if height is None else height
    box = box_quads((-0.5 * size, -0.5 * size, z), (0.5 * size, 0.5 * size, z + height), 1, inward=False)
    c, s = np.cos(np.radians(turn)), np.sin(np.radians(turn))
    turned = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    centre = np.array([0.8 - 0.5 * size, 0.8 - 0.5 * size, 0.0])
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),)) + [(q @ turned.T + centre, m) for q, m in box]
    bulb = np.eye(4)
    bulb[:3, 3] = (-0.4, 0.2, 1.4)
    return quad_scene(quads, [Material("floor", (0.7, 0.7, 0.7)), Material("box", (0.8, 0.3, 0.2))],
                      [Light("bulb", "POINT", (1, 1, 1), 60.0, bulb)], (0.0, -0.95, 1.0), (0.0, 0.5, 0.6),
                      lens=12.0)


def open_room_with_block(block=(0.2, 0.5, 0.8)):
    """An open-topped 2 × 2 × 2 m room with a coloured block, lit by a lamp and a dim sky (two VCT parts)."""
    matrix = np.eye(4)
    matrix[:3, 3] = (-0.5, 0.2, 1.5)
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    quads += box_quads((-0.3, -0.3, 0.0), (0.3, 0.3, 0.7), 1, inward=False)
    return quad_scene(quads, [Material("walls", (0.7, 0.6, 0.5)), Material("block", block)],
                      [Light("lamp", "POINT", (1.0, 0.9, 0.8), 60.0, matrix)], (0.0, -0.9, 1.5), (0.0, 0.5, 0.3),
                      world=(0.05, 0.07, 0.1))
