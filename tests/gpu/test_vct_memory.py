# SPDX-License-Identifier: GPL-3.0-or-later
"""What bench --incremental says the VCT keeps across edits (vct/memory.cached_bytes) against what a render keeps in
its pass cache: the volumes byte for byte, the pools (sized at run time from what the scene holds) within the
estimate's own margin."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct import parts
from bounce_gi.gpu_kernels.vct.memory import cached_bytes
from bounce_gi.gpu_kernels.vct.settings import VctSettings, traced_texels
from bounce_gi.gpu_kernels.voxel.voxelize import scene_area
from support.synthetic import open_room_with_block

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))
DTYPE_BYTES = {"f4": 4, "f2": 2, "u4": 4}


def _level0(textures) -> int:
    return sum(t.width * t.height * t.depth * t.components * DTYPE_BYTES[t.dtype] for t in textures)


def _pool_bytes(pool) -> int:
    return pool.headers.size + pool.next.size + sum(b.size for b in pool.payload.values())


def test_the_estimate_is_what_a_render_keeps():
    scene = open_room_with_block()
    engine = Engine()
    try:
        engine.render(scene, SETTINGS)
        entries = engine.pipeline.cache.entries

        def sizes(ctx):
            geometry = entries["vct_geometry"].value
            return {"voxels": _level0(entries["vct_voxelize"].value.textures().values()),
                    "albedo": _level0(entries["vct_albedo"].value.textures),
                    "parts": sum(_level0(entries[f"vct_inject_{p}"].value.textures)
                                 for p in parts.PARTS if f"vct_inject_{p}" in entries),
                    "centroids": _level0(geometry.centroids), "layers": _level0([geometry.layers]),
                    "steps": _pool_bytes(geometry.gather_pool), "hits": _pool_bytes(entries["vct_hits"].value)}
        kept = engine.worker.call(sizes)
    finally:
        engine.shutdown()
    estimate = dict(zip(("voxels", "albedo", "parts", "centroids", "layers", "steps", "hits"), cached_bytes(
        scene, SETTINGS.vct, traced_texels(SETTINGS.width, SETTINGS.height, SETTINGS.vct), scene_area(scene)).values()))
    print({k: (kept[k], estimate[k]) for k in kept})
    for name in ("voxels", "albedo", "parts", "centroids"):
        assert kept[name] == estimate[name], name
    # The layer volume holds every mip level: level 0 and up to 1/7 more (each level an eighth of the one below).
    assert kept["layers"] <= estimate["layers"] <= kept["layers"] * 8 / 7
    assert kept["hits"] == pytest.approx(estimate["hits"], rel=1e-3)  # sized from the traced texels alone
    # The gathers' pool is sized from the faces counted, the estimate from the surface area at FACES_PER_CELL_AREA
    # (2.2 measured in a box room, rounded up to 2.5): within a third of it.
    assert kept["steps"] == pytest.approx(estimate["steps"], rel=0.33)
