# SPDX-License-Identifier: GPL-3.0-or-later
"""A regular voxel lattice in world space: cubic cells, origin snapped to whole cells (Freed 2018, §4.1).

Freed 2018, §4.1: "to prevent some issues with temporal artifacts, the voxel textures are snapped to a discrete
grid corresponding to the size of each voxel cell in world space". Here that means `origin / cell` is always an
integer, so moving the scene bounds (or, for camera-following cascades, the camera) by less than a cell leaves
every voxel boundary where it was. Grid coordinates: `g = (p − origin) / cell`; voxel (i, j, k) spans
`[i, i+1) × [j, j+1) × [k, k+1)` in grid units and numpy volumes are indexed `[k, j, i]` (z, y, x).
Pure Python/numpy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

CELL_MANTISSA_BITS = 16


def _round_up_mantissa(x: float, bits: int = CELL_MANTISSA_BITS) -> float:
    """The smallest float ≥ x with at most `bits` significant binary digits."""
    m, e = math.frexp(x)
    return math.ldexp(math.ceil(m * 2.0 ** bits) / 2.0 ** bits, e)


@dataclass(frozen=True)
class Grid:
    """`size` = (nx, ny, nz) cubic cells of edge `cell` (m); `origin` = world position of the min corner."""
    origin: tuple
    cell: float
    size: tuple

    def __post_init__(self):
        if not (self.cell > 0 and math.isfinite(self.cell)):
            raise ValueError(f"cell size must be positive and finite, got {self.cell!r}")
        if len(self.size) != 3 or min(self.size) < 1:
            raise ValueError(f"grid size must be 3 positive integers, got {self.size!r}")
        object.__setattr__(self, "origin", tuple(float(c) for c in self.origin))
        object.__setattr__(self, "size", tuple(int(n) for n in self.size))
        object.__setattr__(self, "cell", float(self.cell))

    # -- construction -------------------------------------------------------------------------------------------
    @classmethod
    def fit(cls, lo, hi, resolution: int, margin_cells: int = 1) -> "Grid":
        """The grid enclosing bounds [lo, hi] with `margin_cells` empty cells on each side.

        The longest axis spans `resolution` cells. Snapping the origin down to a whole multiple of `cell` can
        push the max corner up to one cell further, so the cell is sized for `resolution − 2·margin − 1` cells of
        content: L/cell = k whole cells occupy at most k + 1 snapped cells. Other axes get as many cells as their
        extent needs (≤ resolution). A degenerate extent (a single plane or point) gets a 1e-3 m box.
        The cell is rounded up to CELL_MANTISSA_BITS significant bits (a relative change ≤ 2^-16), so bounds that
        only move, or change size by float rounding, keep exactly the same cell and hence the same lattice; it
        also makes origin = integer × cell exact in float64, so origin / cell is an exact integer.
        """
        lo = np.asarray(lo, np.float64)
        hi = np.asarray(hi, np.float64)
        resolution, margin_cells = int(resolution), int(margin_cells)
        inner = resolution - 2 * margin_cells - 1
        if inner < 1:
            raise ValueError(f"resolution {resolution} leaves no room inside {margin_cells} margin cells")
        extent = float(np.max(hi - lo))
        cell = _round_up_mantissa(max(extent, 1e-3) / inner)
        first = np.floor(lo / cell) - margin_cells
        last = np.ceil(hi / cell) + margin_cells
        counts = np.clip(last - first, 1, resolution).astype(int)
        return cls(tuple(first * cell), cell, tuple(counts))

    @classmethod
    def centered(cls, center, cell: float, size) -> "Grid":
        """A grid of `size` cells around `center`, snapped so `origin / cell` is integral (camera cascades).

        Odd sizes put `center` inside the middle voxel; even sizes put the middle lattice point nearest to it.
        """
        center = np.asarray(center, np.float64)
        size = np.broadcast_to(np.asarray(size, int), (3,))
        first = np.floor(center / float(cell) - size / 2.0 + 0.5)
        return cls(tuple(first * float(cell)), float(cell), tuple(int(n) for n in size))

    # -- queries --------------------------------------------------------------------------------------------------
    @property
    def origin_index(self) -> tuple:
        """The origin in whole cells (origin = origin_index · cell)."""
        return tuple(int(round(o / self.cell)) for o in self.origin)

    @property
    def shape_zyx(self) -> tuple:
        """numpy shape of a scalar volume on this grid: (nz, ny, nx)."""
        return self.size[2], self.size[1], self.size[0]

    @property
    def voxel_count(self) -> int:
        return self.size[0] * self.size[1] * self.size[2]

    def world_to_grid(self, p) -> np.ndarray:
        """Continuous grid coordinates (cells) of world points `p` (..., 3); voxel index = floor of it."""
        return (np.asarray(p, np.float64) - np.asarray(self.origin)) / self.cell

    def voxel_index(self, p) -> np.ndarray:
        """Integer (i, j, k) of the voxel containing each point (may lie outside the grid)."""
        return np.floor(self.world_to_grid(p)).astype(np.int64)

    def cell_center(self, i, j, k) -> np.ndarray:
        """World position of the centre of voxel (i, j, k); accepts scalars or arrays."""
        idx = np.stack(np.broadcast_arrays(np.asarray(i), np.asarray(j), np.asarray(k)), axis=-1)
        return np.asarray(self.origin) + (idx + 0.5) * self.cell

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World (min corner, max corner)."""
        o = np.asarray(self.origin)
        return o, o + np.asarray(self.size) * self.cell

    def key(self) -> tuple:
        """Hashable identity for pass caching."""
        return self.origin_index, repr(self.cell), self.size
