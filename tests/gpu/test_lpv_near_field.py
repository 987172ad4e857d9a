# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's cached transport near the surfaces it starts and ends on: where they meet (gpu_kernels/lpv/crossings.py:
the planes each LPV cell's surfaces lie in) and where they curve (lpv/clusters.py polygons: which clusters the
kernel takes as flat octagons), against exact view factors and a closed sphere. The kernel and the visibility are
deterministic, so the bounds are the measured values with a point or two for other drivers' rounding."""
import numpy as np

from bounce_gi.gpu_kernels.scene import Material
from support.lpv_transfer import irradiance, rendered_transfer
from support.synthetic import box_quads, quad, quad_scene, rectangle_view_factor

EMITTING = [Material("lit", (0.5,) * 3, emission=(1.0,) * 3), Material("grey", (0.5,) * 3)]


def _facing_side(e, stored_normals, facing) -> np.ndarray:
    """Each receiver's irradiance on the side that faces `facing` (unit, one per receiver): its front where its
    stored normal (lpv/receivers.py: sign-canonical) points that way, else its back."""
    front = np.einsum("ij,ij->i", stored_normals, facing) > 0
    return np.where(front, e[0], e[1])


def _block_on_floor_irradiance():
    """A 1 m block standing on an 8 m floor at 32³ (a sunlit box on a ground plane, as a user sets one up): the
    transfer's one-bounce irradiance where every floor cluster sends its area's worth of flux (radiosity B = 1), on
    the outside of the block's −y face, and where the −y face's clusters do, on the floor in front of it; each with
    the exact view factors (B = 1: irradiance = view factor) and the receivers' distance from the other surface."""
    lo, hi = np.array([0.0, -0.2, 0.0]), np.array([1.0, 0.8, 1.0])
    floor = quad([(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], (0, 0, 1))
    t = rendered_transfer(quad_scene([(floor, 0)] + box_quads(lo, hi, 1, inward=False), EMITTING, [],
                                     (4.0, -4.5, 3.0), (0.5, 0.3, 0.3)), 32)
    records, axis, at = t.clusters.records, t.rows[:, 3].astype(int), t.rows[:, 8:11]
    middle = (at[:, 0] > lo[0] + 0.1) & (at[:, 0] < hi[0] - 0.1)  # away from the face's side edges
    face = middle & (axis == 1) & (np.abs(at[:, 1] - lo[1]) < 0.05)
    ground = middle & (axis == 2) & (np.abs(at[:, 2]) < 0.05) & (at[:, 1] < lo[1])
    out = []
    for receivers_, senders, rect, normal, distance in (
            (face, records["normal"][:, 2] > 0.99, ((-4, -4, 0), (8, 0, 0), (0, 4 + lo[1], 0)), (0, -1, 0),
             at[:, 2]),
            (ground, (records["normal"][:, 1] < -0.99) & (np.abs(records["position"][:, 1] - lo[1]) < 0.1),
             ((lo[0], lo[1], 0), (1, 0, 0), (0, 0, 1)), (0, 0, 1), lo[1] - at[:, 1])):
        e = irradiance(t, np.where(senders, records["normal"][:, 3], 0.0))
        facing = np.tile(normal, (int(receivers_.sum()), 1)).astype(np.float64)
        lit = _facing_side(e[:, receivers_], t.rows[receivers_, 4:7], facing)
        out.append((lit, rectangle_view_factor(at[receivers_], facing, *rect, m=200), distance[receivers_]))
    return out


def test_a_block_on_a_floor_and_the_floor_at_its_foot_light_each_other():
    """The floor in front of a block's face, lit by the face, and the face, lit by the floor, against the exact view
    factors. The LPV cell at the block's foot holds the floor and a third of the face's height: its normals pass the
    plane test (lpv/crossings.py), and as their mean plane, tilted 22° across the corner, it stopped the light between
    the two: the floor got 0.30 of its view factor within 0.2 m of the face, 0.70 at 0.2–0.35 m, 0.86 at 0.35–0.6 m,
    0.91 at 0.6–1 m, the face 0.75 at 0.2–0.35 m up (a sunlit box's foot on a ground plane: 0.2–0.5 of Cycles'
    Diffuse Indirect). As two axis planes: the floor 0.999–1.001 at every distance, the face 0.978–0.982 (its
    clusters near the floor are wider than the block's face is, as octagons). Bounds 0.97 and 0.95: the kernel is
    deterministic, so about three points for other drivers' rounding; a plane across the corner costs a quarter."""
    face, floor = _block_on_floor_irradiance()
    for name, (e, exact, distance), bound in (("floor", floor, 0.97), ("face", face, 0.95)):
        for lo, hi in ((0.0, 0.2), (0.2, 0.35), (0.35, 0.6), (0.6, 1.0)):
            k = (distance >= lo) & (distance < hi)
            ratio = e[k].sum() / exact[k].sum()
            print(f"{name} {lo}–{hi} m: {ratio:.3f} of the view factor ({k.sum()} receivers)")
            assert k.sum() >= 4 and bound <= ratio <= 1.02


def test_a_closed_spheres_inside_does_not_light_its_outside():
    """A closed sphere (0.8 m, an icosphere of 5120 faces) above an 8 m floor at 32³: its inside's clusters send
    their area's worth of flux each (B = 1). None of it may reach the sphere's outside (Cycles: none), and the inside,
    a closed cavity, should get B. The inside of the sphere's top is a cluster whose mean normal is −z, a cap 0.7 m
    across; taken as flat because that normal lies along an axis, it lit as a square in its mean plane, wider than
    the sphere is there, the outside of the sphere's top from within: 0.45% of B over the outside, 0.84% over the top,
    up to 12.6% on one receiver (a sunlit sphere's top: 1.35× Cycles' Diffuse Indirect; 1.24× now). Planar where its
    normals agree (lpv/clusters.py polygons): 0 everywhere at 512 clusters; at the 1024 this small scene gets now
    (LpvSettings.transfer_pairs) at most 0.0012 on one receiver, 2.6·10⁻⁵ on average (60 of 762 above 10⁻⁴: what
    the shell's fuzzy crossings let through from clusters nearer it). Measured inside: 0.930 (its curved clusters
    as quarter discs).
    Bounds: 0.002 of B outside anywhere (the square put 0.126 there); the inside 0.90 to 1.02."""
    import trimesh

    centre = np.array([0.0, 0.0, 1.0])
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.8)
    floor = quad([(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], (0, 0, 1))
    t = rendered_transfer(quad_scene([(floor, 0), (sphere.vertices[sphere.faces] + centre, 1)], EMITTING, [],
                                     (4.0, -4.5, 3.0), (0.0, 0.0, 0.8)), 32)
    records = t.clusters.records
    at, normal = records["position"][:, :3], records["normal"][:, :3]
    on_sphere = np.abs(np.linalg.norm(at - centre, axis=1) - 0.8) < 0.2
    inside = on_sphere & (np.einsum("ij,ij->i", normal, at - centre) < 0)
    e = irradiance(t, np.where(inside, records["normal"][:, 3], 0.0))
    where, areas = t.rows[:, 8:11], np.asarray(t.areas, np.float64)
    on = np.abs(np.linalg.norm(where - centre, axis=1) - 0.8) < 0.1
    outward = (where[on] - centre) / np.linalg.norm(where[on] - centre, axis=1, keepdims=True)
    outside = _facing_side(e[:, on], t.rows[on, 4:7], outward)
    within = _facing_side(e[:, on], t.rows[on, 4:7], -outward)
    cavity = float((within * areas[on]).sum() / areas[on].sum())
    print(f"closed sphere, B = 1 inside: outside at most {outside.max():.4f}, inside {cavity:.3f}")
    assert inside.sum() > 50 and outside.max() <= 0.002 and 0.90 <= cavity <= 1.02


def test_the_ground_at_a_buildings_foot_is_lit_by_its_facade():
    """A 10 × 14 × 12 m building (a closed box) on a 200 m ground plane at 32³ (fine voxels of 3.4 m: a town block
    as outdoor.py builds it): its −y façade's clusters send B = 1, and the ground receivers of the voxels that the
    façade's plane cuts — ground in front of it and under the building in one voxel — must get the façade's light
    on the strip in front of it, against the exact view factor averaged over that strip (what the pixels there
    read). One receiver of both parts, centred on the façade's plane, got none of it (0.00: the façade's clusters
    light nothing in their own plane); kept on the side the façade faces (lpv/wall_sides.py) it reads 0.98–0.99,
    its centroid's value for a strip whose view factor falls from 0.5 at the wall. Bound 0.9: the kernel is
    deterministic, so a few points for other drivers and for where the grid's voxels fall against the wall."""
    lo, hi = np.array([-19.0, -27.0, 0.0]), np.array([-9.0, -13.0, 12.0])
    ground = quad([(-100, -100, 0), (100, -100, 0), (100, 100, 0), (-100, 100, 0)], (0, 0, 1))
    t = rendered_transfer(quad_scene([(ground, 0)] + box_quads(lo, hi, 1, inward=False), EMITTING, [],
                                     (2.0, -55.0, 1.7), (-2.0, 10.0, 6.0)), 32)
    records = t.clusters.records
    facade = (records["normal"][:, 1] < -0.99) & (np.abs(records["position"][:, 1] - lo[1]) < 0.1)
    e = irradiance(t, np.where(facade, records["normal"][:, 3], 0.0))
    fine, cells, axis = t.clusters.fine, t.rows[:, :3], t.rows[:, 3].astype(int)
    start = np.asarray(fine.origin) + cells * fine.cell  # each receiver's voxel's low corner
    cut = (axis == 2) & (start[:, 1] < lo[1]) & (start[:, 1] + fine.cell > lo[1]) & (start[:, 2] < 0) \
        & (start[:, 0] >= lo[0]) & (start[:, 0] + fine.cell <= hi[0])  # away from the façade's side edges
    up = np.tile((0.0, 0.0, 1.0), (int(cut.sum()), 1))
    lit = _facing_side(e[:, cut], t.rows[cut, 4:7], up)
    s = (np.arange(6) + 0.5) / 6
    exact = []
    for x0, y0 in start[cut, :2]:  # the strip of ground in front of the façade in that voxel
        sx, sy = np.meshgrid(x0 + s * fine.cell, y0 + s * (lo[1] - y0))
        points = np.stack([sx.ravel(), sy.ravel(), np.zeros(sx.size)], axis=1)
        exact.append(rectangle_view_factor(points, np.tile((0.0, 0.0, 1.0), (len(points), 1)),
                                           (lo[0], lo[1], 0), (hi[0] - lo[0], 0, 0), (0, 0, hi[2]), m=60).mean())
    ratio = lit / np.array(exact)
    print(f"ground at the façade's foot: {np.round(ratio, 3)} of the view factor ({cut.sum()} receivers)")
    assert cut.sum() >= 2 and ratio.min() >= 0.9 and ratio.max() <= 1.05
