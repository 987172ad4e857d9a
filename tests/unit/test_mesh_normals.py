# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels/scene.finite_normals (extraction and the engine repair meshes with it): broken corner normals (NaN,
infinite, zero) fall back to the triangle's geometric normal; good ones are kept as they are."""
import numpy as np

from bounce_gi.gpu_kernels.scene import finite_normals


def test_broken_corner_normals_become_the_geometric_normal():
    tri = np.array([[[0, 0, 0], [2, 0, 0], [0, 3, 0]], [[0, 0, 0], [0, 0, 1], [0, 1, 0]]], np.float32)
    good = np.array([0.6, 0.0, 0.8], np.float32)
    normals = np.array([[good, [np.nan, 0, 0], [0, 0, 0]], [good, good, [np.inf, 1, 0]]], np.float32)
    out = finite_normals(tri, normals)
    np.testing.assert_array_equal(out[0, 0], good)
    np.testing.assert_array_equal(out[0, 1:], [[0, 0, 1], [0, 0, 1]])  # counter-clockwise in xy: +z
    np.testing.assert_array_equal(out[1, :2], [good, good])
    np.testing.assert_array_equal(out[1, 2], [-1, 0, 0])  # (0,0,1) × (0,1,0) = −x
    assert np.isfinite(out).all()


def test_finite_normals_are_returned_unchanged():
    tri = np.zeros((1, 3, 3), np.float32)
    normals = np.tile(np.array([0.0, 0.0, 1.0], np.float32), (1, 3, 1))
    assert finite_normals(tri, normals) is normals
