# SPDX-License-Identifier: GPL-3.0-or-later
"""What VCT leaves out where a scene lets it, and says so in "skipped_work" (vct/bounce.skipped_work,
vct/specular.skipped_work): the bounce series stops once a gathered bounce adds less than epsilon of the first
bounce's flux, and all-rough materials run no specular cone."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.synthetic import box_quads, quad_scene


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _room(engine, albedo, roughness):
    """An open-topped room with a block, sunlit, every surface a Principled BSDF of one albedo and roughness, at
    epsilon 0.05."""
    sun = Light("sun", "SUN", (1, 1, 1), 4.0, np.linalg.inv(cam.look_at((1, -1, 3), (0, 0, 0), (0, 0, 1))))
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    quads += box_quads((-0.3, -0.3, 0.0), (0.3, 0.3, 0.7), 0, inward=False)
    scene = quad_scene(quads, [Material("all", (albedo,) * 3, roughness=roughness, specular_layer=True)], [sun],
                       (0.0, -0.9, 1.5), (0.0, 0.5, 0.3))
    vct = VctSettings(resolution=32, indirect_scale=1, epsilon=0.05)
    return engine.render(scene, RenderSettings("vct", 40, 30, vct=vct))


def test_the_bounce_series_stops_where_a_bounce_adds_less_than_epsilon_and_says_so(engine):
    """Albedo 0.05: the second bounce adds about 0.05 × (the share of the first that reaches a surface) of the
    first, under epsilon 0.05, so the series stops after it (no gather, no tail); at albedo 0.7 every bounce adds
    more than that and all four are gathered, then extrapolated to 8. Roughness 1 runs no specular cone; 0.3 does."""
    dark = _room(engine, 0.05, roughness=1.0)
    bounces = dark.info["bounces"]
    assert [b["bounce"] for b in bounces] == [1, 2] and bounces[-1]["stopped"]
    work = " ".join(dark.info["skipped_work"])
    assert "bounces 3-8: the series stopped after 2" in work and "specular cones: no pixel" in work
    bright = _room(engine, 0.7, roughness=0.3)
    assert [b["bounce"] for b in bright.info["bounces"]] == [1, 2, 3, 4, 8]
    assert not any("bounces" in w or "specular" in w for w in bright.info["skipped_work"])
