# SPDX-License-Identifier: GPL-3.0-or-later
"""Shadow-cube faces behind an area light (common/lights.cube_views, `unlit`) are drawn into neither the depth atlas
nor the RSM: the render is the one that draws them, bit for bit, in a room lit by a ceiling light (the +z face of
each of its sample points' cubes is behind it) and after the light moves."""
from dataclasses import replace

import numpy as np

from bounce_gi.gpu_kernels.common import lights
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.synthetic import box_quads, quad_scene

PASSES = ("Combined", "Diffuse Direct", "Diffuse Indirect", "Glossy Direct")


def ceiling_lit_room(x=0.0):
    lamp = np.eye(4)
    lamp[:3, 3] = (x, 0.1, 1.9)  # local −z: facing down
    box = box_quads((-0.3, -0.3, 0.0), (0.2, 0.2, 0.6), 1, inward=False)
    return quad_scene(box_quads((-1, -1, 0), (1, 1, 2), 0) + box,
                      [Material("walls", (0.7, 0.7, 0.7)), Material("box", (0.8, 0.3, 0.2), metallic=1.0, roughness=0.3, specular_layer=True)],
                      [Light("lamp", "AREA", (1, 1, 1), 80.0, lamp, size=0.5)], (0.0, -0.95, 1.0),
                      (0.0, 0.5, 0.6), lens=12.0)


def renders(method):
    engine = Engine()
    try:
        settings = RenderSettings(method, 48, 36)
        first = engine.render(ceiling_lit_room(), settings)
        moved = engine.render(ceiling_lit_room(0.2), settings)
        return [{p: np.asarray(r.passes[p]) for p in PASSES} for r in (first, moved)]
    finally:
        engine.shutdown()


def test_faces_behind_an_area_light_are_skipped_without_changing_the_render(monkeypatch):
    views = lights.build_light_buffers(ceiling_lit_room()).views
    assert sum(v.unlit for v in views) == len(views) // 6 > 0  # one face per sample point's cube
    skipping = {m: renders(m) for m in ("lpv", "vct")}
    cube_views = lights.cube_views
    monkeypatch.setattr(lights, "cube_views", lambda *a, **k: [replace(v, unlit=False) for v in cube_views(*a, **k)])
    assert not any(v.unlit for v in lights.build_light_buffers(ceiling_lit_room()).views)
    for method, frames in skipping.items():
        for got, want in zip(frames, renders(method)):
            for name in PASSES:  # bit for bit
                assert np.array_equal(got[name], want[name]), (method, name)
                assert np.asarray(want[name])[..., :3].max() > 0, (method, name)
