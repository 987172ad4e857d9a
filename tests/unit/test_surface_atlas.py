# SPDX-License-Identifier: GPL-3.0-or-later
"""The surface atlas's layout (gpu_kernels/surface/atlas.py): every texel stands for a point of its own triangle,
tiles never overlap, the budget holds, and the corners' texel coordinates are the ones the texels were laid out
by — the mapping the viewport's fragment shader inverts."""
import numpy as np

from bounce_gi.gpu_kernels.surface.atlas import MAX_TILE, build_atlas
from bounce_gi.gpu_kernels.surface.gbuffer import surface_points
from bounce_gi.tests.support.synthetic import lit_patch_scene


def scene_with_slivers():
    scene = lit_patch_scene("wall beside")
    sliver = np.array([[[0, 0, 5], [4, 0, 5], [4, 0.001, 5]]], np.float32)  # 4 m long, 1 mm wide
    scene.positions = np.concatenate([scene.positions, sliver])
    scene.normals = np.concatenate([scene.normals, np.full((1, 3, 3), (0, 0, 1), np.float32)])
    scene.uvs = np.concatenate([scene.uvs, np.zeros((1, 3, 2), np.float32)])
    scene.material_index = np.concatenate([scene.material_index, [0]]).astype(np.int32)
    return scene


def test_every_texel_stands_for_a_point_of_its_own_triangle_and_tiles_do_not_overlap():
    scene = scene_with_slivers()
    atlas = build_atlas(scene, 20000)
    assert atlas.texel_count <= 20000
    owned = atlas.triangle >= 0
    # Each tile's k × k texels, and no other, belong to its triangle.
    for t, ((x, y), k) in enumerate(zip(atlas.origin, atlas.tile)):
        assert 1 <= k <= MAX_TILE
        assert (atlas.triangle[y:y + k, x:x + k] == t).all()
    assert owned.sum() == atlas.texel_count
    s, t = atlas.bary[..., 0][owned], atlas.bary[..., 1][owned]
    assert (s >= 0).all() and (t >= 0).all() and (s + t <= 1 + 1e-6).all()
    points = surface_points(scene, atlas)
    pos = points["position"][owned]
    lo, hi = scene.bounds()
    assert (pos >= lo - 1e-5).all() and (pos <= hi + 1e-5).all()


def test_corner_texel_coordinates_invert_the_layout():
    # A texel (i, j) of triangle T stands for s = (i + ½)/k, t = (j + ½)/k where that is half a texel or more inside
    # the hypotenuse; interpolating the corners' texel coordinates at that (s, t) must land on the texel's centre.
    atlas = build_atlas(scene_with_slivers(), 5000)
    corners = atlas.corner_texels()
    ys, xs = np.nonzero(atlas.triangle >= 0)
    tri = atlas.triangle[ys, xs]
    s, t = atlas.bary[ys, xs, 0], atlas.bary[ys, xs, 1]
    k = atlas.tile[tri]
    i, j = xs - atlas.origin[tri, 0], ys - atlas.origin[tri, 1]
    inside = (i + j + 1) / k <= 1 - 0.5 / k
    assert inside.sum() > 1000
    np.testing.assert_allclose(s[inside], ((i + 0.5) / k)[inside], atol=1e-6)
    c = corners[tri]
    at = (1 - s - t)[:, None] * c[:, 0] + s[:, None] * c[:, 1] + t[:, None] * c[:, 2]
    np.testing.assert_allclose(at[inside], np.stack([xs, ys], 1)[inside] + 0.5, atol=1e-3)


def test_a_budget_below_one_texel_per_triangle_gives_each_triangle_one():
    scene = scene_with_slivers()
    atlas = build_atlas(scene, 3)
    assert (atlas.tile == 1).all() and atlas.texel_count == scene.triangle_count
