# SPDX-License-Identifier: GPL-3.0-or-later
"""The VCT grid and its volumes: the grid padded so every mip level nests, the six face volumes the injection
and the bounces write, the filtered cone volumes the cones read, and binding those to a program."""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..common.grid import Grid
from ..gl.bind import bind_samplers, set_uniform
from ..scene import Scene
from .settings import VctSettings


def mip_levels(resolution: int) -> int:
    """Levels down to 4 voxels along the longest axis (64 → 5 levels: 64 … 4); cones wider than the coarsest voxel
    sample it with longer steps. Measured with levels down to 1 voxel: Diffuse Indirect rel-L1 at 8 bounces 0.005 –
    0.016 lower on Cornell / spot_room / courtyard, but the white furnace 94.8% → 89.8% of the exact light: texels
    that wide straddle a room's walls, and their mean coverage lets wide cones out."""
    return max(1, int(math.floor(math.log2(resolution))) - 1)


# The bounce gathers read texels no wider than 1/GATHER_TEXEL_FRACTION of the longest axis (gather_levels).
GATHER_TEXEL_FRACTION = 16


def gather_levels(resolution: int) -> int:
    """Levels the bounce gathers (vct/bounce.py) read: texels no wider than 1/16 of the longest axis (64 → 3
    levels: 1, 2 and 4 voxels). A coarser texel straddles a room's walls: its coverage is the mean over its
    cross-section, so a cone reading it passes partly around a wall that no ray could pass, and with each bounce
    gathered through it more light leaves a closed room. Measured, the share of its light the closed white furnace
    keeps per gathered bounce (tests/stress/test_furnace.py's box), all levels → these: 16³ 0.934 → 0.989, 64³
    0.967 → 0.990, 128³ 0.976 → 0.992. The per-pixel cones keep every level: capped there too, cornell_animated's
    Diffuse Indirect came out worse (0.097 → 0.136 against Cycles) at 1.4× the trace's time."""
    coarsest = int(math.floor(math.log2(max(resolution / GATHER_TEXEL_FRACTION, 1.0))))
    return max(1, min(mip_levels(resolution), coarsest + 1))


def vct_grid(scene: Scene, settings: VctSettings) -> Grid:
    """Grid.fit over the scene (1 empty margin voxel, origin snapped to the lattice, Freed 2018, §4.1), each axis
    padded up to a multiple of 2^(levels − 1) so every parent voxel has exactly 8 children at every level and
    the levels' texel centres nest (no half texels at borders)."""
    lo, hi = scene.bounds()
    g = Grid.fit(lo, hi, settings.resolution, margin_cells=1)
    align = 2 ** (mip_levels(settings.resolution) - 1)
    return Grid(g.origin, g.cell, tuple(-(-n // align) * align for n in g.size))


def level_sizes(grid: Grid, levels: int) -> list[tuple]:
    """Voxels per axis at each mip level (exact halvings: vct_grid pads the axes)."""
    return [tuple(int(n) >> level for n in grid.size) for level in range(levels)]


FACE_ALBEDO_BYTES = 6 * 8  # FaceAlbedo: six RGBA16F texels a voxel


@dataclass
class FaceAlbedo:
    """Six RGBA16F 3D textures, one per voxel face (as Faces): rgb = the albedo of the surfaces whose light leaves
    through that face (vct/inject.face_albedo; where none does, its neighbours' or its voxel's other faces'), 0 in
    empty voxels."""
    textures: list
    grid: Grid

    def release(self):
        for t in self.textures:
            t.release()


@dataclass
class Faces:
    """Six RGBA32F 3D textures, one per voxel face (outward normal +x, −x, +y, −y, +z, −z): rgb = outgoing
    radiance through that face (vct/inject.py's own: E/π, the light per unit albedo), a = its coverage α_g
    (vct/inject.glsl). `flux`: π·cell²·Σ α_g·L_g (W, RGB), with `occupied` and `missed`, set on the sum of the
    injected parts (vct/parts.sum_parts)."""
    textures: list
    grid: Grid
    levels: int  # mip levels the volumes built from these faces get
    flux: list = None
    occupied: int = 0
    centroids: list = None  # vct/inject.py only: per face, xyz = where its surface points lie, w = ±α_g
    missed: int = 0  # faces with coverage that caught no raster sample (lit at the face centre instead)
    centroids_owned: bool = True  # False: VoxelGeometry's, kept across light edits

    def release(self):
        for t in self.textures + (self.centroids or [] if self.centroids_owned else []):
            t.release()


@dataclass
class VoxelGeometry:
    """What the VCT passes derive from the geometry alone (the vct_geometry pass, keyed by the geometry, the
    emission, the grid and its levels), made by the first frame that needs each and kept across light, world and
    material colour edits, which would make them again the same: the faces' centroids (vct/inject.py), the layer
    volumes (vct/mipmap.py), the list of faces with coverage and the steps their gathers take (vct/bounce.py). The
    passes' outputs that read them do not own them."""
    centroids: list = None
    layers: object = None
    face_list: tuple = None  # (storage buffer, count)
    gather_pool: object = None  # replay.HitPool of the gathers' steps, keyed by the cone settings (pool.key)

    def release(self):
        for t in (self.centroids or []) + [self.layers] * (self.layers is not None) + list(self.face_list or ())[:1]:
            t.release()
        if self.gather_pool is not None:
            self.gather_pool.release()


@dataclass
class ConeVolumes:
    """Filtered radiance (premultiplied rgb = α·L, a = α) with `levels` mip levels: 1 isotropic texture or 6
    anisotropic ones (direction of travel +x, −x, +y, −y, +z, −z). `owned` False: a view of another pass's
    volumes (the vct_bounce pass with bounces = 1), which must not release them."""
    textures: list
    grid: Grid
    levels: int
    anisotropic: bool
    owned: bool = True
    faces: Faces | None = None  # the bounced face radiance these volumes were built from (vct_bounce only)
    bounce_stats: list = None
    # Anisotropic: where each texel's surfaces lie along each axis (vct/mipmap.glsl MODE_LAYERS). Geometry only, so
    # the bounce passes share the direct light's (layers_owned False).
    layers: object = None
    layers_owned: bool = True

    def release(self):
        if self.owned:
            for t in self.textures:
                t.release()
            if self.faces is not None:
                self.faces.release()
            if self.layers is not None and self.layers_owned:
                self.layers.release()


def bind_volumes(prog, volumes: ConeVolumes, first: int) -> int:
    """Bind the cone volumes (sampler array u_volume, and u_replay0… on the same units) and, anisotropic, their
    layer volume (u_layers) from unit `first`; returns the next free unit."""
    unit = bind_samplers(prog, "u_volume", volumes.textures, first)
    for i in range(len(volumes.textures)):  # the replays read them under other names too (vct/hits.glsl)
        set_uniform(prog, f"u_replay{i}", first + i)
    return bind_samplers(prog, "u_layers", [volumes.layers] if volumes.layers is not None else [], unit)


def voxelize_scene(ctx, programs, scene: Scene, geometry, textures: list, grid: Grid):
    """The shared voxelizer (rasterised, exact areas) on the VCT grid: the surfaces' areas and normals, what the
    geometry alone decides. Its albedo and emission volumes are released (None): the VCT takes each face's albedo
    from vct/inject.face_albedo and its emitters' light from the lights, so a material edit keeps these voxels."""
    from ..voxel.voxelize import voxelize

    vox = voxelize(ctx, programs, scene, geometry, textures, grid)
    for name in ("albedo", "emission"):
        getattr(vox, name).release()
        setattr(vox, name, None)
    return vox
