# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's cached transport where surfaces meet (gpu_kernels/lpv/crossings.py: the planes each LPV cell's surfaces
lie in), against exact view factors: the kernel and the visibility are deterministic, so the bounds are the measured
values less a point or two for other drivers' rounding."""
import numpy as np

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Material
from support.synthetic import box_quads, quad, quad_scene, rectangle_view_factor


def _block_on_floor_irradiance():
    """A 1 m block standing on an 8 m floor at 32³ (a sunlit box on a ground plane, as a user sets one up): the
    transfer's one-bounce irradiance where every floor cluster sends its area's worth of flux (radiosity B = 1), on
    the block's −y face, and where the −y face's clusters do, on the floor in front of it; each with its receivers'
    centroids and the exact view factors (B = 1: irradiance = view factor)."""
    from support.stress import settings

    lo, hi = np.array([0.0, -0.2, 0.0]), np.array([1.0, 0.8, 1.0])
    floor = quad([(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], (0, 0, 1))
    scene = quad_scene([(floor, 0)] + box_quads(lo, hi, 1, inward=False),
                       [Material("lit", (0.5,) * 3, emission=(1.0,) * 3), Material("grey", (0.5,) * 3)], [],
                       (4.0, -4.5, 3.0), (0.5, 0.3, 0.3))
    engine = Engine()
    engine.render(scene, settings("lpv", resolution=32, bounces=1))
    t = engine.pipeline.cache.entries["lpv_transfer"].value[0]
    engine.shutdown()
    records, axis, at = t.clusters.records, t.rows[:, 3].astype(int), t.rows[:, 8:11]
    middle = (at[:, 0] > lo[0] + 0.1) & (at[:, 0] < hi[0] - 0.1)  # away from the face's side edges
    face = middle & (axis == 1) & (np.abs(at[:, 1] - lo[1]) < 0.05)
    ground = middle & (axis == 2) & (np.abs(at[:, 2]) < 0.05) & (at[:, 1] < lo[1])
    out = {}
    for receivers_, senders, rect, normal in (
            (face, records["normal"][:, 2] > 0.99, ((-4, -4, 0), (8, 0, 0), (0, 4 + lo[1], 0)), (0, -1, 0)),
            (ground, (records["normal"][:, 1] < -0.99) & (np.abs(records["position"][:, 1] - lo[1]) < 0.1),
             ((lo[0], lo[1], 0), (1, 0, 0), (0, 0, 1)), (0, 0, 1))):
        flux = np.where(senders, records["normal"][:, 3], 0.0).astype(np.float64)
        e = np.zeros((2, len(t.areas)))
        for side in range(2):
            e[side, t.order[side]] = flux @ t.matrix[side].astype(np.float64)
        points = at[receivers_]
        exact = rectangle_view_factor(points, np.tile(normal, (len(points), 1)), *rect, m=200)
        out[normal[2] == 1] = (e[:, receivers_].max(axis=0), exact, points)
    return out[False], out[True]


def test_a_block_on_a_floor_and_the_floor_at_its_foot_light_each_other():
    """The floor in front of a block's face, lit by the face, and the face, lit by the floor, against the exact view
    factors. The LPV cell at the block's foot holds the floor and a third of the face's height: its normals pass the
    plane test (lpv/crossings.py), and as their mean plane, tilted 22° across the corner, it stopped the light between
    the two: the floor got 0.30 of its view factor within 0.2 m of the face, 0.70 at 0.2–0.35 m, 0.86 at 0.35–0.6 m,
    0.91 at 0.6–1 m, the face 0.75 at 0.2–0.35 m up (a sunlit box's foot on a ground plane: 0.2–0.5 of Cycles'
    Diffuse Indirect). As two axis planes: the floor 0.999–1.001 at every distance, the face 0.978–0.989 (its
    clusters near the floor are wider than the block's face is, as octagons). Bounds 0.97 and 0.95: the kernel is
    deterministic; a point and a half for other drivers' rounding, and a plane across the corner costs a quarter."""
    (face_e, face_exact, face_at), (floor_e, floor_exact, floor_at) = _block_on_floor_irradiance()
    from_face = -0.2 - floor_at[:, 1]
    for name, e, exact, where, bound in (("floor", floor_e, floor_exact, from_face, 0.97),
                                         ("face", face_e, face_exact, face_at[:, 2], 0.95)):
        for lo, hi in ((0.0, 0.2), (0.2, 0.35), (0.35, 0.6), (0.6, 1.0)):
            k = (where >= lo) & (where < hi)
            ratio = e[k].sum() / exact[k].sum()
            print(f"{name} {lo}–{hi} m: {ratio:.3f} of the view factor ({k.sum()} receivers)")
            assert k.sum() >= 4 and bound <= ratio <= 1.02
