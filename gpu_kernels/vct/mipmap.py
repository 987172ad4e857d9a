# SPDX-License-Identifier: GPL-3.0-or-later
"""vct_mipmap: the filtered cone volumes built from the face radiances, level by level (isotropic: the mean of
the children; anisotropic: six directions composited front to back, Crassin et al. 2011's anisotropic voxels),
and the layer volume that says where each texel's surfaces lie along each axis."""
from __future__ import annotations

from ..gl.bind import bind_grid, bind_images, bind_samplers, dispatch, set_uniform, texture3d
from .volumes import ConeVolumes, Faces, VoxelGeometry, level_sizes


def build_volumes(ctx, programs, faces: Faces, anisotropic: bool, into: ConeVolumes | None = None,
                  layers=None, shared: VoxelGeometry | None = None) -> ConeVolumes:
    """Level 0 from the face radiances, then each level from the one below (vct/mipmap.glsl, Freed 2018, §4.4), and,
    anisotropic, the layer volume (from faces.centroids, or `layers` shared from the volumes of the same geometry,
    or `shared`'s, which gets it where it has none). `into`: rebuild existing volumes in place (the vct_bounce pass)
    instead of allocating new ones — volumes built from faces of the same coverage, whose empty voxels hold zeros."""
    grid = faces.grid
    sizes = level_sizes(grid, faces.levels)
    count = 6 if anisotropic else 1
    vols = into or ConeVolumes([texture3d(ctx, grid.size, len(sizes), zero=True) for _ in range(count)], grid,
                               len(sizes), anisotropic)  # level 0 zeroed: MODE_BASE stores covered faces only
    variant = {"MODE_ANISO": None} if anisotropic else {}
    prog = programs.compute("vct/mipmap.glsl", {"MODE_BASE": None, **variant})
    bind_samplers(prog, "u_src", faces.textures, 0)
    bind_images(vols.textures, level=0)
    set_uniform(prog, "u_dst_size", sizes[0])
    dispatch(prog, sizes[0])
    ctx.memory_barrier()
    prog = programs.compute("vct/mipmap.glsl", {"MODE_DOWN": None, **variant})
    bind_samplers(prog, "u_src", vols.textures, 0)
    for level in range(1, len(sizes)):
        bind_images(vols.textures, level=level)
        set_uniform(prog, "u_dst_size", sizes[level])
        set_uniform(prog, "u_level", level)
        dispatch(prog, sizes[level])
        ctx.memory_barrier()
    layers = shared.layers if layers is None and shared is not None else layers
    if anisotropic and layers is not None:
        vols.layers, vols.layers_owned = layers, False
    elif anisotropic and vols.layers is None:
        vols.layers, vols.layers_owned = build_layers(ctx, programs, faces, vols), shared is None
        if shared is not None:
            shared.layers = vols.layers
    return vols


def build_layers(ctx, programs, faces: Faces, vols: ConeVolumes):
    """The layer volume of anisotropic `vols` (vct/mipmap.glsl MODE_LAYERS), every level."""
    grid = faces.grid
    sizes = level_sizes(grid, vols.levels)
    layers = texture3d(ctx, grid.size, len(sizes))
    prog = programs.compute("vct/mipmap.glsl", {"MODE_LAYERS": None})
    unit = bind_samplers(prog, "u_src", vols.textures, 0)
    unit = bind_samplers(prog, "u_centroid", faces.centroids or faces.textures, unit)
    bind_samplers(prog, "u_layers_src", [layers], unit)
    set_uniform(prog, "u_has_centroids", faces.centroids is not None)
    bind_grid(prog, grid)
    for level, size in enumerate(sizes):
        layers.bind_to_image(0, read=False, write=True, level=level)
        set_uniform(prog, "u_dst_size", size)
        set_uniform(prog, "u_level", level)
        dispatch(prog, size)
        ctx.memory_barrier()
    return layers
