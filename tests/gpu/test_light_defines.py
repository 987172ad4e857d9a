# SPDX-License-Identifier: GPL-3.0-or-later
"""ShadowAtlas.defines: a scene without emissive meshes compiles the light programs without the emitters' triangle
lists (NO_TRIANGLE_LISTS, common/light_eval.glsl), which must light it exactly as the full programs do."""
from dataclasses import replace

import numpy as np
import pytest

from bounce_gi.gpu_kernels.direct import shadows
from bounce_gi.gpu_kernels.engine import Engine
from support.stress import box_room, settings


@pytest.mark.parametrize("method", ["lpv", "vct"])
def test_programs_without_triangle_lists_light_an_area_lit_room_as_the_full_ones(monkeypatch, method):
    scene = box_room(kind="AREA")
    s = settings(method, resolution=16)
    specialised = Engine()
    a = specialised.render(scene, s)
    assert specialised.pipeline.cache.entries["shadow_maps"].value.defines == {"NO_TRIANGLE_LISTS": None}
    monkeypatch.setattr(shadows.ShadowAtlas, "defines", property(lambda self: {}))
    full = Engine()
    b = full.render(scene, s)
    for name in ("Diffuse Direct", "Glossy Direct", "Diffuse Indirect"):
        assert np.array_equal(np.asarray(a.passes[name]), np.asarray(b.passes[name])), name
    specialised.shutdown()
    full.shutdown()


def test_a_scene_with_an_emissive_mesh_keeps_the_triangle_lists():
    scene = box_room(kind="AREA")
    lamp = replace(scene.materials[1], emission=(4.0, 3.0, 2.0))
    scene = replace(scene, materials=[scene.materials[0], lamp])
    engine = Engine()
    engine.render(scene, settings("lpv", resolution=16))
    assert engine.pipeline.cache.entries["shadow_maps"].value.defines == {}
    engine.shutdown()
