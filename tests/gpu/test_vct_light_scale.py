# SPDX-License-Identifier: GPL-3.0-or-later
"""VCT's transport per unit of the lights' colours (vct/colours.py): an edit that scales every light alike — the
power or colour of a scene's only lamp — re-runs no VCT pass but the rescale of its results, and any edit gives
what a render from scratch of the edited scene gives. The scaled results are the same float32 products as a cold
render's (its transport runs on the same divided colours), so they agree bitwise; 1e-6 of the largest value leaves
room for a driver that fuses the product differently."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.synthetic import box_quads, quad_scene

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))
TRANSPORT = ("vct_inject", "vct_mipmap", "vct_bounce", "vct_specular", "vct_trace", "vct_upsample")
PASSES = ("Diffuse Indirect", "Glossy Indirect", "AO", "Combined")


def _room(lamps):
    """An open-topped room with a glossy block; `lamps`: (colour, power) of point lights at two places."""
    places = [(-0.5, 0.2, 1.5), (0.6, -0.3, 1.2)]
    lights = []
    for i, (colour, power) in enumerate(lamps):
        matrix = np.eye(4)
        matrix[:3, 3] = places[i]
        lights.append(Light(f"lamp{i}", "POINT", colour, power, matrix))
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    quads += box_quads((-0.3, -0.3, 0.0), (0.3, 0.3, 0.7), 1, inward=False)
    mats = [Material("walls", (0.7, 0.6, 0.5)), Material("block", (0.2, 0.5, 0.8), roughness=0.2,
                                                          specular_layer=True)]
    return quad_scene(quads, mats, lights, (0.0, -0.9, 1.5), (0.0, 0.5, 0.3))


def _same(edited, cold):
    for name in PASSES:
        a, b = edited.passes[name], cold.passes[name]
        assert np.abs(a - b).max() <= 1e-6 * max(float(np.abs(b).max()), 1e-12), name


@pytest.mark.parametrize("edit", [[((1, 1, 1), 60.0)], [((1.0, 0.5, 0.2), 60.0)]], ids=["power", "colour"])
def test_scaling_the_only_light_reruns_no_transport_pass(edit):
    """The only lamp's power (60 → 140 W) or its colour: only the results are rescaled, and they are a cold render's."""
    engine = Engine()
    engine.render(_room([((1, 1, 1), 140.0)]), SETTINGS)
    edited = engine.render(_room(edit), SETTINGS)
    rerun = [k for k in edited.timings if k not in edited.skipped and k != "total"]
    assert not set(TRANSPORT) & set(rerun) and "vct_scale" in rerun, rerun
    assert "vct_bounce" in edited.skipped
    _same(edited, Engine().render(_room(edit), SETTINGS))
    flux = [b["flux"] for b in edited.info["bounces"]]
    cold_flux = [b["flux"] for b in Engine().render(_room(edit), SETTINGS).info["bounces"]]
    assert np.allclose(flux, cold_flux, rtol=1e-6)  # the statistics in watts, not per unit colour


def test_scaling_one_of_two_lights_reruns_the_transport():
    """Two lamps, one made brighter: the divided colours change, the transport runs again, and gives a cold
    render's result."""
    engine = Engine()
    engine.render(_room([((1, 1, 1), 60.0), ((1, 0.9, 0.8), 40.0)]), SETTINGS)
    edited = engine.render(_room([((1, 1, 1), 60.0), ((1, 0.9, 0.8), 90.0)]), SETTINGS)
    assert "vct_bounce" not in edited.skipped and "vct_inject" not in edited.skipped
    _same(edited, Engine().render(_room([((1, 1, 1), 60.0), ((1, 0.9, 0.8), 90.0)]), SETTINGS))
