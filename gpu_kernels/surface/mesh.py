# SPDX-License-Identifier: GPL-3.0-or-later
"""What the viewport draws: the scene's triangles as per-corner vertex arrays, each corner carrying its place in the
surface atlas and its material (shaders/viewport/surface.glsl reads them). Plain numpy."""
from __future__ import annotations

import numpy as np

from ..scene import Scene
from .atlas import SurfaceAtlas

# Vertex attributes, in the order the shader declares them: (name, components).
ATTRIBUTES = (("pos", 3), ("nrm", 3), ("geo", 3), ("tile", 2), ("box", 3), ("tile_i", 2), ("box_i", 3),
              ("mat", 3), ("emission", 3))


def draw_arrays(scene: Scene, atlas: SurfaceAtlas, indirect_atlas: SurfaceAtlas | None = None) -> dict:
    """name → (3·T, C) float32 for every attribute of ATTRIBUTES: world position, shading normal, geometric normal,
    atlas texel coordinate and tile (origin x, y, size) in the direct light's atlas and in the indirect light's
    (`indirect_atlas`, default the same), the material (its index — its rows in common/principled.material_lut —, roughness, Principled or not), the emitted
    radiance."""
    indirect_atlas = indirect_atlas or atlas
    pos = np.asarray(scene.positions, np.float32)
    t = len(pos)
    geo = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    mats = np.array([(i, m.roughness, float(m.specular_layer)) for i, m in enumerate(scene.materials)] or [(0, 0, 0)],
                    np.float32)
    emits = np.array([tuple(m.emission)[:3] for m in scene.materials] or [(0, 0, 0)], np.float32)
    index = np.clip(np.asarray(scene.material_index, np.int64), 0, len(mats) - 1)

    def per_corner(per_triangle):
        return np.repeat(np.asarray(per_triangle, np.float32), 3, axis=0)

    return {"pos": pos.reshape(-1, 3), "nrm": np.asarray(scene.normals, np.float32).reshape(-1, 3),
            "geo": per_corner(geo), "tile": atlas.corner_texels().reshape(-1, 2), "box": per_corner(tile_boxes(atlas)),
            "tile_i": indirect_atlas.corner_texels().reshape(-1, 2), "box_i": per_corner(tile_boxes(indirect_atlas)),
            "mat": per_corner(mats[index]), "emission": per_corner(emits[index])} if t else \
        {name: np.zeros((0, c), np.float32) for name, c in ATTRIBUTES}


def tile_boxes(atlas: SurfaceAtlas) -> np.ndarray:
    """(T, 3) float32: each triangle's tile as (origin x, origin y, size) in texels."""
    return np.hstack([atlas.origin.astype(np.float32), atlas.tile.astype(np.float32)[:, None]])
