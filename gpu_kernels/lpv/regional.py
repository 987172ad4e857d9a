# SPDX-License-Identifier: GPL-3.0-or-later
"""An object's move voxelises again only the part of the grid it left and entered.

The receivers come from three voxelisations of the whole fine grid (lpv/receivers.py), most of a geometry volume's
cost. A voxel's sums depend only on the triangles that cross it (voxel/raster.glsl clips each triangle to its
voxels), so after a move the voxels no moved triangle crosses, before or after, keep their values. The geometry
volume keeps its voxelisation, sparse (`KeptVoxels`: the voxels with a surface), with the triangles and the other
inputs it was made of; the next geometry's voxelisation, where only triangle positions changed, voxelises the box the
moved triangles span before and after (voxelize's `region`, in the whole grid's coordinates, so each of its voxels is
exactly what a voxelisation of the whole grid gives) into a copy of the kept one. Everything after it (the
receivers, the blocking, the visibility planes) is made from the whole arrays as before.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from ..direct.shadows import moved_box
from ..scene import Scene, hash_parts

# A move whose box holds more than this share of the grid's voxels voxelises the whole grid: a region that large
# saves little, and the copy of the kept arrays costs as much as the rest.
REGION_SHARE = 0.5


@dataclass
class KeptVoxels:
    """Per-axis voxelisation arrays (VoxelVolumes.read: {name: (nz, ny, nx, 4)}), sparse: every array is zero where a
    voxel holds no surface, so each axis keeps the flat indices of its voxels with a surface and each array's rows
    there. `positions`: the triangles they were made of; `inputs`: inputs_key of the rest."""
    shape: tuple
    index: list
    rows: list
    positions: np.ndarray
    inputs: str

    @property
    def nbytes(self) -> int:
        return sum(i.nbytes + sum(r.nbytes for r in rows.values()) for i, rows in zip(self.index, self.rows)) + \
            self.positions.nbytes

    def arrays(self) -> list:
        """The dense arrays again, one dict per axis."""
        out = []
        for index, rows in zip(self.index, self.rows):
            axis = {}
            for name, values in rows.items():
                dense = np.zeros(self.shape + (4,), np.float32)
                dense.reshape(-1, 4)[index] = values
                axis[name] = dense
            out.append(axis)
        return out


def keep(arrays: list, scene: Scene, inputs: str) -> KeptVoxels:
    """KeptVoxels of per-axis `arrays` (each with "area") made of `scene`'s triangles and `inputs`."""
    shape = arrays[0]["area"].shape[:3]
    index = [np.flatnonzero(a["area"][..., 3] > 0) for a in arrays]
    rows = [{name: v.reshape(-1, 4)[i] for name, v in a.items()} for a, i in zip(arrays, index)]
    return KeptVoxels(shape, index, rows, np.array(scene.positions, copy=True), inputs)


def inputs_key(scene: Scene, materials) -> str:
    """What a voxelisation reads besides the triangles' positions: their UVs and materials, and the materials'
    state (`materials`: the pipeline's key of their colours and textures)."""
    return hash_parts(scene.uvs, scene.material_index, materials)


def moved_region(kept: KeptVoxels | None, scene: Scene, fine: Grid, inputs: str):
    """The voxels (lo, hi) of `fine` to voxelise again for `scene`, given the voxelisation `kept` of the same grid:
    those the triangles that moved cross, before or after, grown by a voxel (the rasteriser's half-pixel dilation
    and float rounding at the box's faces); None where the whole grid must be: no kept voxelisation, another grid,
    another triangle count or anything but positions changed, nothing moved, or a region over REGION_SHARE."""
    if kept is None or kept.shape != fine.shape_zyx or kept.inputs != inputs:
        return None
    box = moved_box(kept.positions, np.asarray(scene.positions))
    if box is None or box is False:
        return None
    size = np.asarray(fine.size)
    lo = np.clip(fine.voxel_index(box[0]) - 1, 0, size)
    hi = np.clip(fine.voxel_index(box[1]) + 2, 0, size)
    if np.any(hi <= lo) or np.prod(hi - lo) > REGION_SHARE * fine.voxel_count:
        return None
    return like_the_grid(lo, hi, size)


def _pot(n: int) -> bool:
    return n & (n - 1) == 0


def like_the_grid(lo: np.ndarray, hi: np.ndarray, size: np.ndarray) -> tuple:
    """The region (lo, hi) grown, per axis, until its size is a power of two exactly where the grid's is. llvmpipe
    compiles a shader variant for each pattern of power-of-two sizes among the textures a shader binds: a region
    of 16 × 15 × 15 voxels cost the voxeliser 2.2 s the first time (a new variant), one of 17 × 15 × 15 the 42 ms
    of any other (measured, Mesa 22.3.6). Grown alike, a region's textures reuse the variants the whole grid's
    voxelisation compiled."""
    lo, hi = lo.copy(), hi.copy()
    for a in range(3):
        while _pot(int(hi[a] - lo[a])) != _pot(int(size[a])):
            if hi[a] < size[a]:
                hi[a] += 1
            else:
                lo[a] -= 1
    return lo, hi


def paste(arrays: list, region: tuple, part: list) -> list:
    """`arrays` (dense, per axis) with the region's voxels replaced by `part`'s (the region's voxelisation)."""
    (x0, y0, z0), (x1, y1, z1) = (tuple(int(c) for c in v) for v in region)
    for whole, new in zip(arrays, part):
        for name, values in whole.items():
            values[z0:z1, y0:y1, x0:x1] = new[name]
    return arrays
