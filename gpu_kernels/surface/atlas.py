# SPDX-License-Identifier: GPL-3.0-or-later
"""The surface atlas: every triangle gets a square tile of texels, so light can be computed once per surface point,
independent of the view, and looked up by the viewport's fragment shader (ui/draw.py) from any camera.

A triangle's tile is k × k texels; its corners map to the tile's (0, 0), (k, 0) and (0, k), so a point with
barycentric coordinates (s, t) of corners 1 and 2 sits at tile texel coordinate (s·k, t·k) and texel (i, j) stands
for the point s = (i + ½)/k, t = (j + ½)/k. Texels on or past the diagonal (s + t > 1 − ½/k) hold the nearest point
half a texel inside the hypotenuse, as the legs' texels are half a texel inside theirs: they are the gutter that
bilinear filtering reads at that edge, while the fragment shader clamps its lookup to the tile's texel centres so it
never reads a neighbour's tile. This is the layout of
per-triangle texture atlases such as Burley and Lacewell's Ptex ("Ptex: Per-Face Texture Mapping for Production
Rendering", 2008), with one tile per triangle instead of per quad.

k follows the triangle's size (its longer edge from corner 0 over the texel size), from 1 to MAX_TILE; the texel
size is the smallest that keeps the atlas within a texel budget. The atlas holds two pages, one per side of every
surface (two-sided as in Cycles): rows [0, H) light the side the geometric normal points to, rows [H, 2H) the other.
Rows count from the bottom (GL order), like every texture in the pipeline. Plain numpy, no GL.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Scene, hash_parts

MAX_TILE = 1024  # texels along a tile's side: the budget, not this, limits big triangles (a floor quad needs hundreds)
VIEWPORT_TEXELS = 65536  # texels per page of the viewport's final stage (and of `bounce-gi snapshot`)
# The indirect light's atlas has this many times fewer texels than the direct light's (texels twice as wide): it
# varies slowly, and its gather per texel (VCT's cones) is most of the viewport's GI time.
INDIRECT_SHARE = 4
MAX_WIDTH = 4096  # texels per atlas row (within every GL's GL_MAX_TEXTURE_SIZE)


@dataclass
class SurfaceAtlas:
    width: int  # texels per row
    height: int  # rows of one page (the texture is width × 2·height)
    texel: float  # world size of the largest texel (m): the longer edge from corner 0 of a triangle / its k
    origin: np.ndarray  # (T, 2) int32: each triangle's tile, lower-left texel (x, y) in the front page
    tile: np.ndarray  # (T,) int32: k, texels along the tile's side
    triangle: np.ndarray  # (H, W) int32: the triangle a front-page texel belongs to, -1 for none
    bary: np.ndarray  # (H, W, 2) float32: (s, t) of the point the texel stands for
    key: str  # content key of the layout (pass cache)

    @property
    def texel_count(self) -> int:
        return int(np.sum(self.tile.astype(np.int64) ** 2))

    def corner_texels(self) -> np.ndarray:
        """(T, 3, 2) float32: the corners' positions in the front page, in texels — (0, 0), (k, 0), (0, k) from the
        tile's origin. What the viewport interpolates per fragment."""
        k = self.tile.astype(np.float32)[:, None]
        base = self.origin.astype(np.float32)
        return np.stack([base, base + np.hstack([k, 0 * k]), base + np.hstack([0 * k, k])], axis=1)


def edge_lengths(positions: np.ndarray) -> np.ndarray:
    """The longer of the two edges from corner 0 of every triangle (what its tile's side spans)."""
    e1 = np.linalg.norm(positions[:, 1] - positions[:, 0], axis=1)
    e2 = np.linalg.norm(positions[:, 2] - positions[:, 0], axis=1)
    return np.maximum(e1, e2)


def tile_sizes(positions: np.ndarray, texel: float) -> np.ndarray:
    """k per triangle for a texel size: its edge_lengths in texels, 1..MAX_TILE."""
    return np.clip(np.ceil(edge_lengths(positions) / texel), 1, MAX_TILE).astype(np.int32)


def choose_texel(positions: np.ndarray, budget: int) -> float:
    """The smallest texel size (m) whose tiles fit in `budget` texels per page (bisection on a log scale). A budget
    smaller than one texel per triangle gives every triangle one texel."""
    lo, hi = 1e-5, 1e5  # every triangle is MAX_TILE wide at lo, 1 texel at hi
    if int(np.sum(tile_sizes(positions, lo).astype(np.int64) ** 2)) <= budget:
        return lo
    for _ in range(48):
        mid = np.sqrt(lo * hi)
        if int(np.sum(tile_sizes(positions, mid).astype(np.int64) ** 2)) <= budget:
            hi = mid
        else:
            lo = mid
    return float(hi)


def pack_tiles(tile: np.ndarray) -> tuple[np.ndarray, int, int]:
    """Lower-left texel of every tile, packed in shelves, the largest tiles first: a shelf is as tall as its first
    tile, and each column of it stacks tiles of one size up to the shelf's height, so small tiles fill the space
    beside big ones. Returns (origins (T, 2) int32, width, height)."""
    total = int(np.sum(tile.astype(np.int64) ** 2))
    width = int(min(MAX_WIDTH, max(int(tile.max()) if tile.size else 1, -(-int(np.sqrt(total * 1.05)) // 8) * 8)))
    origin = np.zeros((tile.size, 2), np.int32)
    x = shelf_y = shelf_h = 0
    col_x = col_k = col_fill = -1
    for idx in np.argsort(-tile, kind="stable"):
        k = int(tile[idx])
        if k == col_k and col_fill + k <= shelf_h:  # the open column has room for one more
            origin[idx] = (col_x, shelf_y + col_fill)
            col_fill += k
            continue
        if x + k > width:  # a new shelf, as tall as this tile
            shelf_y, shelf_h, x = shelf_y + shelf_h, 0, 0
        shelf_h = max(shelf_h, k)
        col_x, col_k, col_fill = x, k, k
        origin[idx] = (x, shelf_y)
        x += k
    return origin, width, max(1, shelf_y + shelf_h)


def build_atlas(scene: Scene, budget: int) -> SurfaceAtlas:
    """Lay out every triangle of `scene` in at most `budget` texels per page."""
    pos = np.asarray(scene.positions, np.float64)
    texel = choose_texel(pos, budget) if len(pos) else 1.0
    tile = tile_sizes(pos, texel) if len(pos) else np.zeros(0, np.int32)
    origin, width, height = pack_tiles(tile) if len(pos) else (np.zeros((0, 2), np.int32), 1, 1)
    triangle = np.full((height, width), -1, np.int32)
    bary = np.zeros((height, width, 2), np.float32)
    for k in sorted(set(tile.tolist())):
        idx = np.flatnonzero(tile == k)
        j, i = np.mgrid[0:k, 0:k]  # i along x (s), j along y (t)
        s, t = (i + 0.5) / k, (j + 0.5) / k
        # Past the hypotenuse, or on it (the diagonal i + j = k − 1 lands exactly there): the nearest point of the
        # line half a texel inside, as the legs' texels are. A point on an edge is where another surface may
        # meet this one (a wall's top edge under a roof), and its shadow lookup would see past the contact.
        limit = 1 - 0.5 / k
        over = s + t > limit
        s, t = np.where(over, (s - t + limit) / 2, s), np.where(over, (t - s + limit) / 2, t)
        ys = origin[idx, 1][:, None, None] + j[None]
        xs = origin[idx, 0][:, None, None] + i[None]
        triangle[ys, xs] = idx[:, None, None]
        bary[ys, xs, 0], bary[ys, xs, 1] = s[None], t[None]
    key = hash_parts(pos.astype(np.float32), budget)
    size = float(np.max(edge_lengths(pos) / tile)) if len(pos) else 0.0
    return SurfaceAtlas(width, height, size, origin, tile, triangle, bary, key)
