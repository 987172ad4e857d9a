# SPDX-License-Identifier: GPL-3.0-or-later
"""What the VCT keeps from one frame to the next so that an edit re-runs less, in GPU memory: the structures the
geometry alone decides (kept across light, world and material edits), the faces' albedo (across light and world
edits) and the lights' parts (across the other parts' edits and material edits). `bench --incremental` prints it
at a few grid sizes (issue: "say what the cache costs in GPU memory at 32³/64³/128³")."""
from __future__ import annotations

import math

from ..scene import Scene
from .parts import FACE_BYTES, parts_bytes, scene_parts
from .replay import hits_bytes, steps_bytes
from .settings import VctSettings
from .volumes import FACE_ALBEDO_BYTES, level_sizes, mip_levels, vct_grid

RGBA32F = 16  # bytes a texel of the voxels' and the layer volume's textures


def cached_bytes(scene: Scene, settings: VctSettings, traced: tuple, area: float) -> dict:
    """{structure: bytes} for `scene` (`area` m² of surface) on the grid `settings` give it, the per-pixel trace at
    `traced` = (w, h) texels. The pools at their first size (vct/replay.py)."""
    grid = vct_grid(scene, settings)
    voxels = grid.voxel_count
    mip_voxels = sum(math.prod(size) for size in level_sizes(grid, mip_levels(settings.resolution)))
    return {
        "voxels: areas, normals (vct_voxelize)": 2 * RGBA32F * voxels,
        "faces' albedo (vct_albedo)": FACE_ALBEDO_BYTES * voxels,
        "lights' parts, light per unit albedo (vct_inject_*)": parts_bytes(grid, scene_parts(scene)),
        "faces' centroids (vct_geometry)": FACE_BYTES * voxels,
        "layer volume, every level (vct_geometry)": RGBA32F * mip_voxels,
        "bounce gathers' steps (vct_geometry)": steps_bytes(area, grid.cell),
        "per-pixel sub-rays' hits (vct_hits)": hits_bytes(traced),
    }
