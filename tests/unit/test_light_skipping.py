# SPDX-License-Identifier: GPL-3.0-or-later
"""Lights that cannot light the scene are left out of the light buffers and reported (gpu_kernels/common/lights.py
unreachable, render --json "skipped_work"): zero power or colour, and a one-sided area light facing away from the
whole scene. Anything else — however dim or far — is kept."""
import numpy as np

from bounce_gi.gpu_kernels.common.lights import build_light_buffers, unreachable
from bounce_gi.gpu_kernels.scene import Light, Material
from support.synthetic import box_quads, quad_scene


def _area(z, facing_down=True):
    m = np.eye(4)
    m[2, 3] = z
    if not facing_down:  # the light shines along local −Z: flip it to shine up
        m[:3, :3] = np.diag([1.0, -1.0, -1.0])
    return Light("panel", "AREA", (1, 1, 1), 50.0, m, size=0.5)


def _scene(lights):
    return quad_scene(box_quads((-1, -1, 0), (1, 1, 2), 0), [Material("white")], lights, (0, -0.9, 1), (0, 0, 1))


def test_lights_that_cannot_light_the_scene_are_skipped_and_named():
    point = Light("bulb", "POINT", (1, 1, 1), 10.0, np.eye(4))
    off = Light("off", "POINT", (1, 1, 1), 0.0, np.eye(4))
    black = Light("black", "SUN", (0, 0, 0), 3.0, np.eye(4))
    above_facing_up = _area(5.0, facing_down=False)  # over the box, shining away from it
    above_facing_down = _area(5.0)  # over the box, shining at it: kept, however far
    scene = _scene([point, off, black, above_facing_up, above_facing_down])
    assert [unreachable(scene, light) for light in scene.lights] == [
        "", "zero power", "zero power", "faces away from the whole scene", ""]
    buffers = build_light_buffers(scene)
    assert len(buffers.lights) == 2
    assert buffers.skipped == ["light 'off': zero power", "light 'black': zero power",
                               "light 'panel': faces away from the whole scene"]
