# SPDX-License-Identifier: GPL-3.0-or-later
"""The RSM drawn a batch of untextured materials at a time (direct/geometry.material_batches, each vertex carrying
its material index) is the RSM drawn one material at a time, texel for texel, and so is what it lights."""
from dataclasses import replace

import numpy as np

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv import rsm
from bounce_gi.gpu_kernels.scene import Material, Texture
from support.lpv_transfer import indirect
from test_lpv_object_move import SETTINGS
from support.synthetic import room_with_box


def mixed_materials():
    """The room with its triangles spread over four materials: three without a texture (two of them neighbours in
    the vertex buffer, so they batch) and a checker-textured one between them."""
    scene = room_with_box(0.0)
    checker = np.zeros((2, 2, 4), np.float32)
    checker[..., 3] = 1.0
    checker[0, 0, :3] = checker[1, 1, :3] = (0.9, 0.2, 0.1)
    checker[0, 1, :3] = checker[1, 0, :3] = (0.1, 0.3, 0.8)
    index = np.arange(len(scene.material_index)) % 4
    uvs = np.tile(np.array([[0.1, 0.1], [0.9, 0.1], [0.9, 0.9]], np.float32), (len(index), 1, 1))
    materials = [Material("a", (0.7, 0.7, 0.7)), Material("b", (0.2, 0.6, 0.3)), Material("tex", base_color_texture=0),
                 Material("metal", (0.9, 0.6, 0.3), metallic=1.0, roughness=0.3)]
    return replace(scene, material_index=index.astype(np.int32), materials=materials, uvs=uvs,
                   textures=[Texture("checker", checker, interpolation="Closest")])


def rsm_texels(engine, name: str) -> np.ndarray:
    """One of the engine's RSM targets, (texels, 4), read on its GPU thread (which owns the context)."""
    maps = engine.pipeline.cache.entries["rsm"].value
    return engine.worker.call(lambda ctx: np.frombuffer(getattr(maps, name).read(), np.float32).reshape(-1, 4))


def test_batched_rsm_draws_are_the_per_material_draws(monkeypatch):
    scene = mixed_materials()
    batched = Engine()
    a = batched.render(scene, SETTINGS)
    drawn = []
    monkeypatch.setattr(rsm, "material_batches", lambda s, geometry, t: drawn.append(1) or geometry.ranges)
    single = Engine()
    b = single.render(scene, SETTINGS)
    assert drawn, "the per-material draws were not used"
    texels = {name: [rsm_texels(e, name) for e in (batched, single)] for name in ("position", "normal", "albedo")}
    assert len(batched.pipeline.cache.entries["rsm"].value.geometry.ranges) == 4
    lit = [p[:, 3] > 0.5 for p in texels["position"]]  # a texel no surface covers holds no value worth comparing
    assert np.array_equal(lit[0], lit[1]) and lit[0].sum() > 1000
    for name, (x, y) in texels.items():
        assert np.array_equal(x[lit[0]], y[lit[0]]), name
    assert set(np.unique(texels["albedo"][0][lit[0], 3]).astype(int)) == {0, 1, 2, 3}  # every material drawn
    assert np.array_equal(indirect(a), indirect(b))
    batched.shutdown()
    single.shutdown()
