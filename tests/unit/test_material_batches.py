# SPDX-License-Identifier: GPL-3.0-or-later
"""direct/geometry.material_batches: neighbouring ranges of untextured materials merge into one draw; a textured
material, or a gap, starts a new one."""
import numpy as np

from bounce_gi.gpu_kernels.direct.geometry import GeometryBuffers, material_batches
from bounce_gi.gpu_kernels.scene import Material, Scene


def test_untextured_neighbours_merge_and_textured_materials_stay_alone():
    materials = [Material("a"), Material("b"), Material("tex", base_color_texture=0), Material("c"), Material("d"),
                 Material("missing", base_color_texture=5)]
    scene = Scene(np.zeros((0, 3, 3), np.float32), np.zeros((0, 3, 3), np.float32), np.zeros((0, 3, 2), np.float32),
                  np.zeros(0, np.int32), materials)
    ranges = [(0, 0, 6), (1, 6, 12), (2, 18, 3), (3, 21, 6), (4, 27, 3), (5, 30, 9)]
    geometry = GeometryBuffers(None, None, None, ranges)
    # one texture: "missing" names an image there is not, so it draws untextured and merges with its neighbours
    assert material_batches(scene, geometry, [object()]) == [(0, 0, 18), (2, 18, 3), (3, 21, 18)]
    assert material_batches(scene, geometry, []) == [(0, 0, 39)]  # no images: every material untextured
    gap = GeometryBuffers(None, None, None, [(0, 0, 6), (1, 9, 3)])
    assert material_batches(scene, gap, []) == [(0, 0, 6), (1, 9, 3)]
