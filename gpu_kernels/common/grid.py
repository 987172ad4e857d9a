# SPDX-License-Identifier: GPL-3.0-or-later
"""A regular voxel lattice in world space: cubic cells, origin snapped to a fixed lattice (Freed 2018, §4.1).

Freed 2018, §4.1: "to prevent some issues with temporal artifacts, the voxel textures are snapped to a discrete
grid corresponding to the size of each voxel cell in world space". Here that means `origin / cell − LATTICE_PHASE`
is always an integer for a fitted grid (and a cascade's origin lies on its coarse grid's lattice), so moving the
scene bounds (or, for camera-following cascades, the camera) by less than a cell leaves every voxel boundary where
it was. Grid coordinates: `g = (p − origin) / cell`; voxel (i, j, k) spans
`[i, i+1) × [j, j+1) × [k, k+1)` in grid units and numpy volumes are indexed `[k, j, i]` (z, y, x).
Pure Python/numpy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

CELL_MANTISSA_BITS = 16
# Grid.fit puts voxel boundaries at (k + 1/3)·cell, not at whole cells: scenes put surfaces at round coordinates
# (a floor at z = 0 above all), and a surface exactly on a boundary falls into the voxel above or below it as float
# rounding decides — differently when the scene is scaled by 10⁴ than by 1 (the LPV came out 4% different). A third
# is never a dyadic fraction, so 0 also stays off the boundaries of the half-size (LPV surface voxels) and
# coarser (VCT mip) lattices.
LATTICE_PHASE = 1.0 / 3.0


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

        The longest axis spans `resolution` cells. Snapping the origin down to the lattice (k + LATTICE_PHASE)·cell
        can push the max corner up to one cell further, so the cell is sized for `resolution − 2·margin − 1` cells of
        content: L/cell = k whole cells occupy at most k + 1 snapped cells. Other axes get as many cells as their
        extent needs (≤ resolution). A degenerate extent (a point) gets a box of 10⁻⁶ of its distance from the origin.
        The cell is rounded up to CELL_MANTISSA_BITS significant bits (a relative change ≤ 2^-16), so bounds that
        only move, or change size by float rounding, keep exactly the same cell and hence the same lattice.
        """
        lo = np.asarray(lo, np.float64)
        hi = np.asarray(hi, np.float64)
        resolution, margin_cells = int(resolution), int(margin_cells)
        inner = resolution - 2 * margin_cells - 1
        if inner < 1:
            raise ValueError(f"resolution {resolution} leaves no room inside {margin_cells} margin cells")
        extent = float(np.max(hi - lo))
        # The cell is strictly larger than extent / inner, so the bounds' max corner never lands exactly on a cell
        # boundary: when extent / inner happened to be exact (a scene scaled by 100) and otherwise not (scaled by
        # 0.001), a wall at the max corner fell into the next voxel or not, and the LPV came out 13% different.
        floor = max(1e-6 * float(np.max(np.abs(np.concatenate([lo, hi])))), 1e-12)  # relative, never in metres
        cell = _round_up_mantissa(max(extent, floor) / inner * (1.0 + 2.0 ** -CELL_MANTISSA_BITS))
        first = np.floor(lo / cell - LATTICE_PHASE) - margin_cells
        last = np.ceil(hi / cell - LATTICE_PHASE) + margin_cells
        counts = np.clip(last - first, 1, resolution).astype(int)
        return cls(tuple((first + LATTICE_PHASE) * cell), cell, tuple(counts))

    @classmethod
    def centered(cls, center, cell: float, size, anchor=(0.0, 0.0, 0.0)) -> "Grid":
        """A grid of `size` cells around `center`, snapped so `(origin − anchor) / cell` is integral (camera
        cascades: anchored at the coarse grid's origin, so their cells nest in its cells).

        Odd sizes put `center` inside the middle voxel; even sizes put the middle lattice point nearest to it.
        """
        center, anchor = np.asarray(center, np.float64), np.asarray(anchor, np.float64)
        size = np.broadcast_to(np.asarray(size, int), (3,))
        first = np.floor((center - anchor) / float(cell) - size / 2.0 + 0.5)
        return cls(tuple(anchor + first * float(cell)), float(cell), tuple(int(n) for n in size))

    # -- queries --------------------------------------------------------------------------------------------------
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
        return tuple(repr(o) for o in self.origin), repr(self.cell), self.size
