# SPDX-License-Identifier: GPL-3.0-or-later
"""An area light's shadow cube leaves out the faces that see only directions behind the light
(common/lights.cube_views, one_sided): exactly those, checked against directions sampled over each face's view."""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common.lights import cube_views


def _face_directions(view, n=21):
    """Unit directions over the whole of a cube face's view (its margin included), world space."""
    s = np.linspace(-view.half_extent, view.half_extent, n)
    x, y = np.meshgrid(s, s)
    local = np.stack([x.ravel(), y.ravel(), -np.ones(x.size)], axis=1)  # view space: right, up, back
    d = local @ view.view_matrix[:3, :3]  # rows of world → view: back to world
    return d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.parametrize("tilt", [0.0, 20.0, 40.0, 45.0, 50.0, 90.0])
def test_unlit_faces_are_those_wholly_behind_the_light(tilt):
    """A light facing down, tilted `tilt` degrees about x: a face is left out iff every direction it covers is
    behind the light (cos ≤ 0). Facing down, the +z face is; tilted 40° still; at 45° none is (each face sees some
    of the light's front); at 50° the −y face is, and facing along +y (90°) that one alone."""
    t = math.radians(tilt)
    normal = np.array([0.0, math.sin(t), -math.cos(t)])
    views = cube_views(np.zeros(3), 384, 0.01, 10.0, normal, 0.25, one_sided=True)
    behind = [bool((_face_directions(v) @ normal <= 1e-12).all()) for v in views]
    assert [v.unlit for v in views] == behind
    assert sum(behind) == (0 if tilt == 45.0 else 1)
    assert not any(v.unlit for v in cube_views(np.zeros(3), 384, 0.01, 10.0, normal, 0.25))  # two-sided emitters
