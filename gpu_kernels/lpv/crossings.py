# SPDX-License-Identifier: GPL-3.0-or-later
"""Where each LPV cell's surfaces lie, for the gathered transports' visibility (lpv/gather.glsl transmittance): a ray
that crosses them inside the cell is stopped by the fraction of the cell they cover.

A cell whose surfaces are one plane (the area-weighted normal tensor Σ A·n·nᵀ has one dominant direction, λ_max /
trace ≥ PLANAR: a wall, a floor, a patch of a sphere) is that plane — normal n (the principal axis, sign-free).
Otherwise (an edge or corner where a floor meets a wall, a pillar) it is three axis planes, one per axis. Axis planes
alone would turn a sphere into a staircase that rays leaving it at a grazing angle cross; one mean plane alone would
put a diagonal wall across every corner. So where the surfaces' positions are known (the cached transport), a cell
whose surfaces face along the axes and lie in two or three flat axis layers (a floor and the foot of a wall, where
the cell holds little of the wall) is axis planes even where its normals pass PLANAR: as their mean plane, tilted
across the corner, it stopped the light between the floor and the wall — a block's face lit the floor at its foot
with 0.30 of the exact view factor (tests/gpu/test_lpv_near_field.py).

Along each plane direction the cell's surfaces form one layer, at their mean coordinate, or two, at their nearest
and farthest coordinates, where every surface lies at one or the other and those lie more than LAYER_GAP apart (the
two faces of a pillar or a wall thinner than a cell, but thicker than a rug; not a curved patch, whose surfaces fill
the range between): one mean plane between a pillar's faces let light into it past both, and out again.

Which crossings belong to a ray's own ends: the plane of a receiver's or a source's own surface passes through it.
A single layer is its surfaces' mean, off each of them by up to half the cell (an edge, a curved patch, the voxels'
centres where the positions are unknown): a crossing within END_CELLS of an end is that end's own. Each of two layers
lies where its surfaces do (`Surfaces`: the cached transport's voxelisation, voxelize positions=True): a crossing
within END_SLACK of an end is its own, and the other face stops the ray.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from ..gl.bind import bind_named

PLANAR = 0.9  # a cell whose surfaces' normals share one plane this closely (λ_max / trace) is one oblique plane
LAYER_GAP = 0.25  # cells: surfaces of one direction further apart than this along it are two layers
END_CELLS = 0.5  # cells: an end's own crossing, surfaces known only to their voxels
END_SLACK = 0.05  # cells: an end's own crossing, surfaces where they lie
FLAT = 0.05  # cells: a layer whose surfaces spread less than this along its axis is a plane
AXIS_ALIGNED = 1.05  # a cell's projected areas / its area, at most, where its surfaces face along the axes
FIELDS = ("coverage", "layers", "layers_far")
# The largest distance to a surface stored in an empty cell (mark_empty_space): a ray skips at most this many
# cells less one at a time; larger gains little (a room's interior is rarely further from a wall).
SKIP_CELLS = 16


@dataclass
class Surfaces:
    """Where the surfaces of each fine voxel lie (voxelize positions=True), in fine voxels from its min corner: the
    `centroid` of all of them ((nz, ny, nx, 3)), and per axis a the centroid along a of those whose dominant axis is a
    (`axis_centroid`, NaN where there are none), and the box they span (`lo`, `hi`)."""
    centroid: np.ndarray
    axis_centroid: np.ndarray
    lo: np.ndarray  # the box all of them span
    hi: np.ndarray


def crossing_layers(area: np.ndarray, normal: np.ndarray, grid: Grid, surfaces: Surfaces | None = None) -> dict:
    """FIELDS → (nz, ny, nx, 4) float32 arrays, in cells from the grid origin, packed for lpv/gather.glsl (two fetches
    a cell, a third where an axis has two layers). Plane cells: coverage (n, −covered share), layers (far layer, end,
    far share, near layer); axis cells: coverage (per axis covered share, box_code), layers (per axis near layer, end),
    layers_far (per axis far layer). The end is negative where a direction has two layers; empty cells are zero
    but for coverage's w, their distance to the nearest surface's cell (mark_empty_space).
    From fine voxel arrays `area` (rgb projected areas, a total) and `normal`. LPV cell c holds fine voxels
    [2c + 1, 2c + 3) along each axis; only the cells holding a surface are worked on (a room's are a fifth)."""
    cells = _Cells.of(area, grid)
    weights = cells.gather(area).astype(np.float64)  # per direction: the axes' projected areas, then the total
    n = cells.gather(normal)[..., :3].astype(np.float64)
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-30)
    corner = cells.corners()  # per fine voxel: its min corner, in cells
    if surfaces is None:
        centre = axis_at = corner + 0.25
    else:
        centre = corner + cells.gather(surfaces.centroid) / 2
        own = cells.gather(surfaces.axis_centroid)
        axis_at = np.where(np.isnan(own), centre, corner + own / 2)
    tensor = cells.sum(weights[..., 3, None, None] * n[..., :, None] * n[..., None, :])
    eigval, eigvec = np.linalg.eigh(tensor)  # ascending
    planar = (cells.sum(weights[..., 3]) > 0) & (eigval[..., 2] >= PLANAR * np.maximum(eigval.sum(axis=-1), 1e-30))
    plane_n = eigvec[..., :, 2]
    coords = np.concatenate([axis_at, (centre * cells.up(plane_n)).sum(axis=-1)[..., None]], -1)
    cov, near, far, end, spread = (np.stack(v, axis=-1) for v in zip(*[
        _layers(weights[..., d], coords[..., d], grid.cell ** 2, cells, surfaces is not None) for d in range(4)]))
    # an axis cell whose every layer is flat holds planes that meet (a floor and a wall), not a curve cut into planes
    flat = np.all((spread[..., :3] <= FLAT) | (cov[..., :3] <= 0), axis=-1)
    if surfaces is None:
        end = np.where(end < 0, -END_CELLS, END_CELLS)
        flat[:] = False
        box = None
    else:  # and two or three flat axis layers are axis planes even where their normals pass PLANAR (see above)
        planar &= ~(flat & ((cov[..., :3] > 0).sum(axis=-1) >= 2) & _axis_aligned(weights, cells))
        lo, hi = (corner + cells.gather(getattr(surfaces, k)) / 2 for k in ("lo", "hi"))
        occupied = (weights[..., 3:] > 0)
        box = (cells.reduce(np.where(occupied, lo, np.inf), "min"), cells.reduce(np.where(occupied, hi, -np.inf), "max"),
               cells.index)
    out = {k: cells.scatter(v) for k, v in _pack(planar, plane_n, cov, near, far, end, flat, surfaces is not None,
                                                 box).items()}
    mark_empty_space(out["coverage"])
    return out


def _axis_aligned(weights: np.ndarray, cells: _Cells) -> np.ndarray:
    """Per cell: do its surfaces, taken together, face along the axes? Their projected areas along the three add up
    to their area, within AXIS_ALIGNED (a surface θ from an axis adds cos θ + sin θ − 1 of its own area: 0.41 at
    45°). A cell mostly of a wall turned off the axes does not, though its slivers read as flat along x and y alike;
    a floor with the foot of a turned wall taking a tenth of the cell's area still does."""
    return cells.sum(weights[..., :3].sum(axis=-1)) <= AXIS_ALIGNED * cells.sum(weights[..., 3])


def mark_empty_space(coverage: np.ndarray) -> None:
    """In place: the w of each cell lpv/gather.glsl finds empty (no plane, no axis coverage) set to its Chebyshev
    distance to the nearest cell that is not (empty_distance), so that a ray there may skip the cells within
    distance − 1, which are all empty too (Cohen and Sheffer 1994, "Proximity clouds": empty-space skipping by a
    distance map). Empty cells' w is free: plane cells' is negative, axis cells' holds their box_code."""
    full = occupied(coverage)
    coverage[..., 3] = np.where(full, coverage[..., 3], empty_distance(full))


def occupied(coverage: np.ndarray) -> np.ndarray:
    """Per cell of a coverage array (…, 4): whether lpv/gather.glsl finds a surface in it (a plane, or axis
    coverage)."""
    return (coverage[..., 3] < 0) | (coverage[..., :3] > 0).any(axis=-1)


def empty_distance(occupied: np.ndarray, cap: int = SKIP_CELLS) -> np.ndarray:
    """Per cell of a (nz, ny, nx) mask: the Chebyshev (L∞) distance in cells to the nearest True cell, 0 on those,
    at most `cap` (also where there is none), float32. By repeated one-cell dilations (each separable per axis)."""
    d = np.full(occupied.shape, float(cap), np.float32)
    reached = occupied.copy()
    d[reached] = 0.0
    for k in range(1, cap):
        if reached.all() or not reached.any():
            break
        grown = reached.copy()
        for axis in range(3):
            before, view = np.moveaxis(grown.copy(), axis, 0), np.moveaxis(grown, axis, 0)
            view[1:] |= before[:-1]
            view[:-1] |= before[1:]
        d[grown & ~reached] = float(k)
        reached = grown
    return d


@dataclass
class _Cells:
    """The LPV cells holding a surface (M of them, `index` (M, 3) xyz) and their eight fine voxels each: arrays
    (M, 8, …) per fine voxel, (M, …) per cell."""
    shape: tuple  # (nz, ny, nx)
    index: np.ndarray
    flat: np.ndarray  # (M,) their index in the dense (nz, ny, nx) grid

    @staticmethod
    def of(area: np.ndarray, grid: Grid) -> "_Cells":
        nx, ny, nz = grid.size
        total = area[1:2 * nz + 1, 1:2 * ny + 1, 1:2 * nx + 1, 3].reshape(nz, 2, ny, 2, nx, 2).sum(axis=(1, 3, 5))
        z, y, x = np.nonzero(total > 0)
        return _Cells((nz, ny, nx), np.stack([x, y, z], axis=-1), np.ravel_multi_index((z, y, x), (nz, ny, nx)))

    def gather(self, fine: np.ndarray) -> np.ndarray:
        """(M, 8, …) of a fine voxel array (2nz + 2, 2ny + 2, 2nx + 2, …): each cell's voxels in (z, y, x) order."""
        nz, ny, nx = self.shape
        inner = fine[1:2 * nz + 1, 1:2 * ny + 1, 1:2 * nx + 1].reshape(nz, 2, ny, 2, nx, 2, *fine.shape[3:])
        x, y, z = self.index.T
        return inner[z, :, y, :, x].reshape(len(self.flat), 8, *fine.shape[3:])

    def corners(self) -> np.ndarray:
        """(M, 8, 3): each fine voxel's min corner, in cells from the grid origin (xyz)."""
        d = np.stack(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij"), -1).reshape(8, 3)[:, ::-1]  # (z, y, x)
        return self.index[:, None, :] + d[None] / 2.0

    def reduce(self, values, how):
        return getattr(values, how)(axis=1)

    def sum(self, values):
        return self.reduce(values, "sum")

    def up(self, values):  # per cell → per fine voxel
        return values[:, None]

    def scatter(self, values: np.ndarray) -> np.ndarray:
        """Per cell (M, …) → the dense (nz, ny, nx, …) grid, zero where no surface is."""
        out = np.zeros((int(np.prod(self.shape)),) + values.shape[1:], values.dtype)
        out[self.flat] = values
        return out.reshape(self.shape + values.shape[1:])


def _layers(weight, coord, cell_area, cells: _Cells, known: bool):
    """For one direction of every cell (fine voxels' `weight`, the area they present across it, and `coord` along
    it): coverage (weight / cell², at most 1; two layers each half of it: the two faces of one pillar or wall),
    near and far layer, end (negative for two layers) and spread (of one layer's surfaces along it). Two layers, at
    the nearest and the farthest surfaces, where those lie more than LAYER_GAP apart and every surface at one or the
    other, and where the surfaces are `known` (not just their voxels' centres); else one, at the weighted mean."""
    has = weight > 0
    lo = cells.reduce(np.where(has, coord, np.inf), "min")
    hi = cells.reduce(np.where(has, coord, -np.inf), "max")
    total = cells.sum(weight)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.nan_to_num(cells.sum(weight * coord) / total)
        spread = np.nan_to_num(hi - lo, nan=0.0, posinf=0.0, neginf=0.0)
    # two layers: every surface near the nearest or the farthest (a solid's two faces), none in between (a curve)
    off = np.minimum(np.abs(coord - cells.up(lo)), np.abs(coord - cells.up(hi)))
    between = np.nan_to_num(cells.reduce(np.where(has, off, 0.0), "max"), nan=np.inf)
    two = (spread > LAYER_GAP) & (between <= 0.5 * LAYER_GAP) & known  # voxels' centres: a surface's steps
    end = np.where(two, -END_SLACK, END_CELLS)
    cover = np.minimum(np.where(two, 0.5, 1.0) * total / cell_area, 1.0)  # two layers: the faces of one solid
    return cover, np.where(two, lo, mean), np.where(two, hi, mean), end, np.where(two, 0.0, spread)


def box_code(box_lo: np.ndarray, box_hi: np.ndarray, base: np.ndarray) -> np.ndarray:
    """The box (cells from the grid origin) a cell's surfaces span, in 1/16 of the cell, as one integer per cell
    (exact in float32): 1 + lo_x + 16 lo_y + 16² lo_z + 16³ hi_x + 16⁴ hi_y + 16⁵ hi_z, hi the last sixteenth it
    reaches into; 0 without a box (the whole cell). Rounded outwards, so the box holds every surface. `base`: the
    cells' xyz."""
    with np.errstate(invalid="ignore"):
        lo = np.clip(np.floor((box_lo - base) * 16), 0, 15)
        hi = np.clip(np.ceil((box_hi - base) * 16) - 1, 0, 15)
    lo, hi = np.nan_to_num(lo).astype(np.int64), np.nan_to_num(hi, nan=15).astype(np.int64)
    code = 1 + sum(lo[..., i] << (4 * i) for i in range(3)) + sum(hi[..., i] << (12 + 4 * i) for i in range(3))
    return np.where(np.isfinite(box_lo).all(axis=-1), code, 0)


def _pack(planar, plane_n, cov, near, far, end, flat, known, box=None) -> dict:
    """The textures' layout (crossing_layers), from per-direction arrays (…, 4): the axes', then the plane's."""
    shape = planar.shape + (4,)
    coverage, layers, layers_far = (np.zeros(shape, np.float32) for _ in range(3))
    axes, plane = ~planar, planar
    coverage[axes, :3] = cov[axes, :3]
    if box is not None:  # axis cells: the box their surfaces span (box_code), where w is free
        coverage[axes, 3] = box_code(*box)[axes]
    layers[axes, :3] = near[axes, :3]
    layers_far[axes, :3] = far[axes, :3]
    # Axis cells hold an edge or a corner, or a curved surface cut into axis planes (a sphere's staircase): a ray
    # leaving a surface there may cross another axis' plane anywhere in the cell, so, one layer per axis, the end's
    # own crossings are those within END_CELLS — of a curve's every plane, of flat planes only the one the end's own
    # surface lies along (END_CELLS + 1: `flat`); a second layer (a pillar's far face) lies where its surface does,
    # END_SLACK (lpv/gather.glsl reads which axes have one from layers_far). Negative: some axis has two.
    axis_end = END_CELLS + np.where(flat, 1.0, 0.0)
    layers[axes, 3] = np.where((end[..., :3] < 0).any(axis=-1), -axis_end, axis_end)[axes]
    coverage[plane] = np.concatenate([plane_n[plane], -cov[plane, 3:]], axis=-1)
    # a plane cell's end, likewise + 1 where its plane is only an end's own if that end's surface lies along it
    plane_end = np.where(known, np.sign(end[..., 3]) * (np.abs(end[..., 3]) + 1.0), end[..., 3])
    layers[plane] = np.stack([far[plane, 3], plane_end[plane], cov[plane, 3], near[plane, 3]], axis=-1)
    occupied = (cov > 0).any(axis=-1)
    for o in (coverage, layers, layers_far):
        o[~occupied] = 0.0
    return {"coverage": coverage, "layers": layers, "layers_far": layers_far}


def volume_fields(ctx, arrays: dict) -> dict:
    """GeometryVolume's keyword fields: a NEAREST-filtered RGBA32F texture per crossing_layers array."""
    import moderngl

    out = {}
    for key, a in arrays.items():
        t = ctx.texture3d(a.shape[2::-1], 4, np.ascontiguousarray(a, np.float32).tobytes(), dtype="f4")
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
        out[key] = t
    return out


def bind_visibility(prog, gv, unit: int = 0) -> int:
    """Point lpv/gather.glsl's visibility samplers at geometry volume `gv`'s crossing planes; the next free unit."""
    names = {"coverage": "u_coverage", "layers": "u_layers", "layers_far": "u_layers_far"}
    return bind_named(prog, [(names[k], getattr(gv, k)) for k in FIELDS], unit)
