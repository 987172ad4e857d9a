# SPDX-License-Identifier: GPL-3.0-or-later
"""What the VCT passes derive from the geometry alone — the faces' centroids, the layer volume, the list of faces
with coverage (vct/volumes.VoxelGeometry, the vct_geometry pass) — is made once and kept across light, world and
material colour edits: the edited render uses the same objects, still alive after the outputs that read them were
replaced, and gives what a render from scratch gives; a geometry edit makes them anew."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from bounce_gi.gpu_kernels.vct.trace import read_level
from support.synthetic import box_quads, quad_scene

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))


def _room(lamp=(-0.3, 0.2, 1.5), block=0.0, world=(0.0, 0.0, 0.0), red=(0.8, 0.2, 0.1)):
    matrix = np.eye(4)
    matrix[:3, 3] = lamp
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    quads += box_quads((-0.3 + block, -0.3, 0.0), (0.3 + block, 0.3, 0.7), 1, inward=False)
    return quad_scene(quads, [Material("white", (0.7, 0.7, 0.7)), Material("red", red)],
                      [Light("bulb", "POINT", (1, 1, 1), 60.0, matrix)], (0.0, -0.9, 1.5), (0.0, 0.5, 0.3),
                      world=world)


def _parts(engine):
    entries = engine.pipeline.cache.entries
    return entries["vct_geometry"].value, entries["vct_inject"].value, entries["vct_bounce"].value


@pytest.mark.parametrize("edit", [dict(lamp=(0.5, -0.4, 1.2)), dict(world=(0.4, 0.5, 0.7)),
                                  dict(red=(0.1, 0.6, 0.2))], ids=["light move", "world colour", "material colour"])
def test_light_edits_keep_the_geometry_parts(edit):
    engine = Engine()
    try:
        engine.render(_room(), SETTINGS)
        shared, faces, _ = _parts(engine)
        assert shared.centroids is faces.centroids and shared.layers is not None and shared.face_list[1] > 1000
        layers, face_list = shared.layers, shared.face_list
        result = engine.render(_room(**edit), SETTINGS)
        assert "vct_geometry" in result.skipped and "vct_inject" not in result.skipped
        kept, faces, bounced = _parts(engine)
        assert kept is shared and faces.centroids is shared.centroids and bounced.layers is layers
        assert kept.face_list is face_list

        def read(ctx):  # alive: the injection that made them was released by the edit
            return [read_level(ctx, engine.pipeline.programs, t, faces.grid, 0) for t in kept.centroids + [layers]]
        assert all(np.isfinite(a).all() for a in engine.worker.call(read))
    finally:
        engine.shutdown()
    cold = Engine()
    try:
        want = cold.render(_room(**edit), SETTINGS)
    finally:
        cold.shutdown()
    for name in ("Diffuse Indirect", "Combined", "AO"):
        # the injection's float sums may differ in the last bit from run to run (vct/inject_raster.glsl)
        got, ref = result.passes[name], want.passes[name]
        assert np.abs(got - ref).max() <= 1e-5 * float(np.abs(ref).max()), name


def test_a_geometry_edit_makes_them_anew():
    engine = Engine()
    try:
        engine.render(_room(), SETTINGS)
        shared, _, _ = _parts(engine)
        result = engine.render(_room(block=0.2), SETTINGS)
        fresh, faces, bounced = _parts(engine)
        assert "vct_geometry" not in result.skipped and fresh is not shared
        assert faces.centroids is fresh.centroids and bounced.layers is fresh.layers
    finally:
        engine.shutdown()
