# SPDX-License-Identifier: GPL-3.0-or-later
"""The shadow atlas: every light's shadow views packed as square tiles into one depth texture, and the GPU records
(VIEW_DTYPE, common/lights.py) that tell the shaders where each view's tile lies."""
from __future__ import annotations

import math

import numpy as np

from .lights import VIEW_DTYPE, ShadowView


def pack_views(views: list[ShadowView], tiles: list[tuple], atlas_size: tuple[int, int], pcf_radius: int,
               view_lights: list | None = None) -> np.ndarray:
    """ShadowView list + atlas tiles (x, y, w, h in texels) → VIEW_DTYPE records (info.w = the view's light)."""
    out = np.zeros(len(views), VIEW_DTYPE)
    aw, ah = atlas_size
    for i, (v, (x, y, w, h)) in enumerate(zip(views, tiles)):
        # GLSL mat4 is column-major: store the transpose of the row-major numpy matrix.
        out[i]["view_projection"] = v.view_projection.T
        out[i]["tile"] = (x / aw, y / ah, w / aw, h / ah)
        out[i]["origin"] = (*v.origin, 1.0 if v.ortho else 0.0)
        # The atlas may have shrunk the tile: a texel then covers resolution/w times more ground.
        light = view_lights[i] if view_lights is not None else 0
        out[i]["info"] = (v.texel_world * v.resolution / w, pcf_radius if v.pcf_radius is None else v.pcf_radius,
                          v.far, light)
        if v.emit_normal is not None:
            out[i]["emitter"] = (*v.emit_normal, v.emit_share)
    return out


def allocate_atlas(resolutions: list[int], width: int = 4096, max_height: int = 16384):
    """Shelf-pack square tiles (largest first). Returns (tiles in input order, atlas size, scale applied)."""
    scale = 1
    while max(resolutions, default=0) // scale > width:  # a tile must fit the atlas width
        scale *= 2
    while True:
        if scale > 1 << 16:
            raise ValueError(f"{len(resolutions)} shadow views do not fit a {width}x{max_height} atlas")
        res = [max(16, r // scale) for r in resolutions]
        order = sorted(range(len(res)), key=lambda i: -res[i])
        tiles = [None] * len(res)
        x = y = shelf = 0
        side = 1 << max(4, math.ceil(math.log2(math.sqrt(sum(r * r for r in res)) + 1)))
        atlas_w = min(width, max(max(res, default=16), side))
        for i in order:
            r = res[i]
            if x + r > atlas_w:
                x, y, shelf = 0, y + shelf, 0
            tiles[i] = (x, y, r, r)
            x += r
            shelf = max(shelf, r)
        height = max(y + shelf, 16)
        if height <= max_height:
            return tiles, (atlas_w, height), scale
        scale *= 2
