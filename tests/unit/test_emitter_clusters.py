# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.common.emitters (issue 17): every emissive triangle in exactly one shadowed cluster, the clusters and
their shadow cubes bounded for any number of triangles, flat clusters, and closed emitters' trapped sides."""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import emitters as em
from bounce_gi.gpu_kernels.common import atlas
from bounce_gi.gpu_kernels.common import lights as lb
from bounce_gi.gpu_kernels.common import shells
from bounce_gi.gpu_kernels.scene import Camera, Material, Scene
from bounce_gi.tests.support.synthetic import closed_cylinder


def cylinder(segments=24, radius=0.22, height=0.32, centre=(0.0, 0.0, 1.5), caps=True):
    return closed_cylinder(segments, radius, height, centre, caps)


def scene_of(*parts):
    """parts: (triangles, material); one material per part."""
    pos = np.concatenate([p for p, _ in parts]).astype(np.float32)
    mats = np.concatenate([np.full(len(p), i, np.int32) for i, (p, _) in enumerate(parts)])
    n = np.zeros_like(pos)
    return Scene(pos, n, np.zeros((len(pos), 3, 2), np.float32), mats, [m for _, m in parts])


def lamp(strength=5.0, albedo=0.0):
    return Material("lamp", (albedo,) * 3, emission=(strength,) * 3)


def floor(z=0.0, size=3.0):
    s = size
    return np.array([[[-s, -s, z], [s, -s, z], [s, s, z]], [[-s, -s, z], [s, s, z], [-s, s, z]]], np.float32)


def soup(count, seed=1):
    """`count` small random triangles scattered in a 10 m cube, none sharing vertices."""
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-5, 5, (count, 1, 3))
    return (centre + rng.normal(scale=0.05, size=(count, 3, 3))).astype(np.float32)


CASES = {
    "lamp shade (92)": lambda: scene_of((cylinder(), lamp())),
    "one quad": lambda: scene_of((floor(2.0, 0.25), lamp())),
    "fine cylinder (4000)": lambda: scene_of((cylinder(1000), lamp())),
    "soup (5000)": lambda: scene_of((soup(5000), lamp())),
    "100 coloured quads": lambda: scene_of(*[(floor(0.1 * k, 0.05) + np.float32(k % 10), Material(
        f"m{k}", emission=(1.0 + k, 1.0, 0.5))) for k in range(100)]),
}


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("budget", [8, 64])
def test_every_emissive_triangle_is_in_exactly_one_cluster_and_the_cost_is_bounded(case, budget):
    scene = CASES[case]()
    idx, _ = em.emissive_triangles(scene)
    clusters = em.cluster_emitters(scene, budget // 2, budget // 2)
    members = np.concatenate([c.triangles for c in clusters])
    assert sorted(members.tolist()) == sorted(idx.tolist())  # all covered, none twice
    assert len(clusters) <= budget // 2
    # Sample points: two cubes each (one per side), or one on a closed shell, which emits outwards only and may have
    # twice as many points (common/emitters.samples_per_side).
    cubes = sum(len(c.sample_points) * (1 if c.one_sided.all() else 2) for c in clusters)
    assert cubes <= budget
    for c in clusters:
        assert 1 <= len(c.sample_points) <= em.MAX_SAMPLES_PER_SIDE * (2 if c.one_sided.all() else 1)
        assert c.sample_areas.sum() == pytest.approx(c.area, rel=1e-9)
    buffers = lb.build_light_buffers(scene, lb.ShadowSettings(emissive_sample_budget=budget))
    assert len(buffers.views) <= 6 * budget  # shadow cubes within the budget
    assert len(buffers.lights) == len(clusters)
    assert buffers.warnings == []


def test_sample_points_lie_on_their_cluster_s_surface():
    scene = scene_of((cylinder(), lamp()))
    for c in em.cluster_emitters(scene, 32, 32):
        for p, n in zip(c.sample_points, c.sample_normals):
            # On the plane of some triangle of the cluster whose normal is n, within that triangle.
            a, b, d = c.vertices[:, 0], c.vertices[:, 1], c.vertices[:, 2]
            nn = np.cross(b - a, d - a)
            nn /= np.linalg.norm(nn, axis=1, keepdims=True)
            on = (np.abs(((p - a) * nn).sum(1)) < 1e-9) & (np.abs(np.abs(nn @ n) - 1) < 1e-9)
            assert on.any()


def test_a_lamp_shade_is_split_by_orientation_and_its_clusters_are_flat():
    clusters = em.cluster_emitters(scene_of((cylinder(), lamp())), 32, 32)
    for c in clusters:
        cross = np.cross(c.vertices[:, 1] - c.vertices[:, 0], c.vertices[:, 2] - c.vertices[:, 0])
        n = cross / np.linalg.norm(cross, axis=1, keepdims=True)
        # Within FLAT_DEGREES of the cluster's normal (sign-free), and no cluster holds both caps or opposite walls.
        assert np.abs(n @ c.normal).min() >= math.cos(math.radians(em.FLAT_DEGREES)) - 1e-9
        height = c.vertices.reshape(-1, 3) @ c.normal
        assert height.max() - height.min() < 0.1


def test_clusters_do_not_depend_on_the_scene_s_scale_or_position():
    a = em.cluster_emitters(scene_of((cylinder(), lamp())), 32, 32)
    b = em.cluster_emitters(scene_of((cylinder() * np.float32(1000) + np.float32(50), lamp())), 32, 32)
    assert [sorted(c.triangles.tolist()) for c in a] == [sorted(c.triangles.tolist()) for c in b]


def test_a_cluster_may_mix_materials_and_keeps_each_triangle_s_radiance():
    quads = [(floor(0.0, 0.1) + np.float32([0.3 * k, 0, 0]), Material(f"m{k}", emission=(k + 1.0, 2.0, 0.0)))
             for k in range(40)]
    scene = scene_of(*quads)
    buffers = lb.build_light_buffers(scene, lb.ShadowSettings(emissive_sample_budget=8))
    assert len(buffers.lights) <= 4
    total = 0
    for rec in buffers.lights:
        first, count, two_sided, is_list = rec["polygon"]
        assert two_sided == 1.0 and is_list == 1.0
        rows = buffers.polygon_vertices[int(first):int(first + count)].reshape(-1, 4, 4)
        radiance = rows[:, 3, :3] * rec["color_type"][:3]
        total += len(rows)  # every triangle's absolute radiance is its material's:
        assert set(np.round(radiance[:, 0]).astype(int)) <= set(range(1, 41))
        np.testing.assert_allclose(radiance[:, 1], 2.0, rtol=1e-6)
        np.testing.assert_allclose(radiance[:, 2], 0.0)
    assert total == 80


@pytest.mark.parametrize("caps", [False, True])
def test_views_carry_each_sample_s_normal_and_share(caps):
    """An open cylinder emits from both sides: the two sides of each sample point emit along opposite normals, and
    each side's shares sum to 1. A closed one (with its caps) emits outwards only: one sample per point, facing out."""
    centre = np.array([0.0, 0.0, 1.5])
    buffers = lb.build_light_buffers(scene_of((cylinder(caps=caps), lamp())))
    packed = atlas.pack_views(buffers.views, [(0, 0, 16, 16)] * len(buffers.views), (16, 16), 1, buffers.view_lights)
    for i, rec in enumerate(buffers.lights):
        first, samples, per = int(rec["params"][1]), int(rec["params"][2]), int(rec["params"][3])
        e = packed["emitter"][first:first + samples * per:per]
        np.testing.assert_allclose(np.linalg.norm(e[:, :3], axis=1), 1.0, rtol=1e-6)
        if not caps:
            np.testing.assert_allclose(e[0::2, :3], -e[1::2, :3], atol=1e-6)
            assert e[0::2, 3].sum() == pytest.approx(1.0, rel=1e-5)
        else:
            origins = np.array([buffers.views[first + k * per].origin for k in range(samples)])
            assert np.all(((origins - centre) * e[:, :3]).sum(axis=1) > 0)
            assert e[:, 3].sum() == pytest.approx(1.0, rel=1e-5)


# --------------------------------------------------------------------------- closed emitters: trapped light

def test_a_closed_shade_s_inner_samples_are_trapped_and_its_outer_ones_are_not():
    clusters = em.cluster_emitters(scene_of((cylinder(), lamp()), (floor(), Material("floor"))), 32, 32)
    centre = np.array([0.0, 0.0, 1.5])
    for c in clusters:
        for (point, normal, _, trapped) in em.side_samples(c):
            inward = (point - centre) @ normal < 0 if abs(normal[2]) < 0.5 else normal[2] * (point[2] - 1.5) < 0
            assert trapped == inward


def _camera_at(scene, point):
    m = np.eye(4)
    m[:3, 3] = point
    scene.camera = Camera(m)
    return scene


@pytest.mark.parametrize("what", ["open cylinder", "camera inside the shade", "dome around the scene and camera"])
def test_open_emitters_and_emitters_around_the_camera_trap_nothing(what):
    if what == "open cylinder":
        scene = scene_of((cylinder(caps=False), lamp()), (floor(), Material("floor")))
    elif what == "camera inside the shade":  # like the white furnace: the inside is what the camera sees
        scene = _camera_at(scene_of((cylinder(), lamp()), (floor(), Material("floor"))), (0.05, 0.0, 1.5))
    else:  # a closed emissive dome around a floor and the camera
        scene = _camera_at(scene_of((cylinder(24, 10.0, 8.0, (0, 0, 1.0)), lamp()), (floor(), Material("floor"))),
                           (1.0, -2.0, 1.5))
    assert not any(c.sample_trapped.any() for c in em.cluster_emitters(scene, 32, 32))


def test_what_lies_inside_a_closed_shade_does_not_open_it():
    """A bulb in the shade (or the end of the lamp's pole) is lit by the inner light, but seen only from inside too:
    the shade still traps its inner light for a camera outside — and only the shade's inner samples are trapped."""
    parts = (cylinder(), lamp()), (floor(1.5, 0.05), Material("bulb")), (floor(), Material("floor"))
    scene = _camera_at(scene_of(*parts), (2.0, -2.0, 1.5))
    clusters = em.cluster_emitters(scene, 32, 32)
    assert sum(int(c.sample_trapped.sum()) for c in clusters) == sum(len(c.sample_points) for c in clusters)
    assert all(c.sample_trapped[:, 0].sum() + c.sample_trapped[:, 1].sum() == len(c.sample_points) for c in clusters)


def test_closedness_needs_every_edge_shared():
    comp, closed = shells.mesh_components(cylinder().astype(np.float64))
    assert closed.tolist() == [True] and set(comp.tolist()) == {0}
    comp, closed = shells.mesh_components(cylinder()[:-1].astype(np.float64))  # one cap triangle missing
    assert closed.tolist() == [False]
    two = np.concatenate([cylinder(), cylinder(centre=(2, 0, 1.5))]).astype(np.float64)
    comp, closed = shells.mesh_components(two)
    assert closed.tolist() == [True, True] and comp[0] != comp[-1]


def test_inside_closed_by_ray_parity():
    shell = cylinder(centre=(0, 0, 0)).astype(np.float64)
    points = np.array([[0, 0, 0], [0.21, 0, 0.1], [0.23, 0, 0], [0, 0, 0.17], [5, 5, 5]], np.float64)
    assert shells.inside_closed(shell, points).tolist() == [True, True, False, False, False]


@pytest.mark.parametrize("flipped", ["none", "some", "all"])
def test_a_closed_shell_is_wound_outwards_whatever_its_windings(flipped):
    """shells.outward turns every triangle of a closed surface to face out, from any mix of windings: two shades,
    one of them half flipped at random, the other wholly, and every normal must point away from its own shade's axis
    (sides) or centre plane (caps)."""
    centres = [np.array([0.0, 0.0, 1.5]), np.array([2.0, 0.0, 1.5])]
    tri = np.concatenate([cylinder(centre=tuple(c)) for c in centres]).astype(np.float64)
    half = len(tri) // 2
    flip = {"none": np.zeros(len(tri), bool), "some": np.random.default_rng(3).random(len(tri)) < 0.5,
            "all": np.arange(len(tri)) >= half}[flipped]
    tri[flip] = tri[flip][:, [0, 2, 1]]
    out = shells.outward(tri)
    normal = np.cross(out[:, 1] - out[:, 0], out[:, 2] - out[:, 0])
    centre = np.where((np.arange(len(tri)) < half)[:, None], centres[0], centres[1])
    away = out.mean(axis=1) - centre
    side = np.abs(normal[:, 2]) < 0.5 * np.linalg.norm(normal, axis=1)
    away[side, 2] = 0.0  # a side's normal points away from the axis
    away[~side, :2] = 0.0  # a cap's away from the middle
    assert np.all((normal * away).sum(axis=1) > 0)
    assert np.allclose(np.sort(out.reshape(len(out), -1), axis=1), np.sort(tri.reshape(len(tri), -1), axis=1))


def test_a_closed_emitter_emits_outwards_only_and_creates_no_trapped_cubes():
    """The shade's triangles are one-sided (common/emitters.py: its inner light stays inside), and the light
    buffers hold cubes only for its outer samples; an open cylinder stays two-sided."""
    closed = scene_of((cylinder(), lamp()), (floor(), Material("floor")))
    clusters = em.cluster_emitters(closed, 32, 32)
    assert all(c.one_sided.all() for c in clusters)
    buffers = lb.build_light_buffers(closed)
    half = lb.ShadowSettings().emissive_sample_budget // 2
    outer = sum(len(c.sample_points) for c in em.cluster_emitters(closed, half, half))
    assert len(buffers.views) == 6 * outer
    assert all(v.emit_share > 0 for v in buffers.views)
    open_ = scene_of((cylinder(caps=False), lamp()), (floor(), Material("floor")))
    assert not any(c.one_sided.any() for c in em.cluster_emitters(open_, 32, 32))


@pytest.mark.parametrize("case", ["one quad", "lamp shade (92)", "100 coloured quads"])
def test_emitter_cubes_share_a_fixed_texel_budget(case):
    """Few cubes keep sample_cube_resolution; many get smaller faces, so that all of them together stay within
    ShadowSettings.emissive_texels and never push the atlas past its size (which halves every light's maps)."""
    s = lb.ShadowSettings()
    buffers = lb.build_light_buffers(CASES[case](), s)
    texels = sum(v.resolution ** 2 for v in buffers.views)
    assert texels <= s.emissive_texels
    assert all(v.resolution % 16 == 0 for v in buffers.views)
    if len(buffers.views) * s.sample_cube_resolution ** 2 <= s.emissive_texels:
        assert {v.resolution for v in buffers.views} == {s.sample_cube_resolution}
    else:  # as fine as the budget allows: the next multiple of 16 would outgrow it
        assert len(buffers.views) * (buffers.views[0].resolution + 16) ** 2 > s.emissive_texels
