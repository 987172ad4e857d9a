# SPDX-License-Identifier: GPL-3.0-or-later
"""vct_inject: the direct light arriving at every voxel face. Surface points are rasterised along their dominant
axis and lit exactly as the Diffuse Direct pass lights pixels (direct/eval.glsl), then averaged per face (Crassin et
al. 2011 inject direct light from shadow maps into the voxels; here each voxel face is lit itself). The faces'
albedo is made apart from the same points (face_albedo), so a material's colour edit keeps the light; the radiance
a face reflects is their product (vct/parts.sum_parts).
Emission itself is never injected (emissive triangles are lights, so their light is in E already), and the light a
closed emitter traps inside itself is left out (common/emitters.py: it would leak out through the voxels)."""
from __future__ import annotations

import math

import numpy as np

from ..common.lights import SKY_INJECTION_STRIDE
from ..direct.geometry import POSITION_ONLY, POSITION_UV, draw_by_material
from ..gl.bind import (VOLUME_GROUP, bind_grid, bind_lights, bind_samplers, dispatch, dispatch_counted, set_uniform,
                       set_uniforms, texture3d, zero_texture)
from ..scene import Scene
from .volumes import FaceAlbedo, Faces, VoxelGeometry


INJECT_SAMPLES = 2  # raster samples per voxel edge: ~4 surface points per voxel face; slivers fall back (vct_inject)
# Sums a voxel face's accumulator holds (the shaders' ACC_CHANNELS): the light's Σw·E/π, Σw, Σw·p; the albedo's
# Σw·albedo, Σw.
LIGHT_SUMS, ALBEDO_SUMS = 8, 4
COVER_TEST_BYTES = 256 * 2 ** 20  # the front-most images' budget (32 MiB at 64³); larger grids skip the cover test


def inject(ctx, programs, scene: Scene, geometry, textures: list, vox, shadows, levels: int,
           shared: VoxelGeometry | None = None, scratch: dict | None = None) -> Faces:
    """Direct light arriving at every voxel face, E/π per unit albedo: surface points rasterised along their
    dominant axis and lit exactly as in direct/light.glsl (vct/inject_raster.glsl), then averaged per face
    (vct/inject.glsl); the statistics (flux, occupied, missed) are taken of the sum (vct/parts.sum_parts). The
    faces' centroids are taken from `shared` where it holds them, else made and left there. `scratch` (a dict;
    none: made and released here) keeps the accumulator and the front-most surfaces for the next injection of the
    same voxels with other lights (vct/parts.py): the caller releases it (release_scratch)."""
    grid = vox.grid
    kept = shared is not None and shared.centroids is not None
    faces = Faces([texture3d(ctx, grid.size, zero=True) for _ in range(6)], grid, levels,
                  centroids=shared.centroids if kept else [texture3d(ctx, grid.size, zero=True) for _ in range(6)],
                  centroids_owned=not kept)
    own = scratch is None
    scratch = {} if own else scratch
    try:
        acc = _accumulator(ctx, grid, scratch, LIGHT_SUMS)
        front_surfaces(ctx, programs, (scene, geometry, textures), grid, scratch)
        _raster_pass(ctx, programs, {}, (scene, geometry, textures), shadows, grid, scratch)
        for outputs, defines in ((faces.textures, {}),) + (() if kept else ((faces.centroids,
                                                                              {"WRITE_CENTROIDS": None}),)):
            prog = _resolve_program(programs, {"MODE_RESOLVE": None, **defines}, vox, acc, shadows, grid, outputs)
            if defines:
                dispatch(prog, grid.size)
                ctx.memory_barrier()
            else:
                run_listed(ctx, prog, grid.size, lambda: _resolve_program(
                    programs, {"MODE_FALLBACK": None}, vox, acc, shadows, grid, outputs))
    finally:
        if own:
            release_scratch(scratch)
    if shared is not None and not kept:
        shared.centroids, faces.centroids_owned = faces.centroids, False
    return faces


def _accumulator(ctx, grid, scratch: dict, channels: int):
    """The raster's sums (vct/inject_raster.glsl: `channels` a face, LIGHT_SUMS or ALBEDO_SUMS), zeroed:
    `scratch`'s, or made and left there."""
    import moderngl

    if "acc" not in scratch:
        nx, ny, nz = grid.size
        scratch["acc"] = ctx.texture3d((channels * nx, ny, 6 * nz), 1, dtype="u4")
        scratch["acc"].filter = (moderngl.NEAREST, moderngl.NEAREST)
    zero_texture(ctx, scratch["acc"])
    return scratch["acc"]


def release_scratch(scratch: dict) -> None:
    """Release what inject() left in `scratch`."""
    for t in [scratch.pop("acc", None)] + list(scratch.pop("fronts", None) or []):
        if t is not None:
            t.release()


def front_surfaces(ctx, programs, drawn: tuple, grid, scratch: dict) -> list:
    """The front-most surfaces of `drawn` = (scene, geometry, textures) per raster column, voxel layer and side
    (front_images, filled by vct/inject_raster.glsl MODE_FRONT): `scratch`'s, or made and left there. They depend
    on the geometry alone, so the albedo pass and every injection of a frame share them."""
    if "fronts" not in scratch:
        scratch["fronts"] = front_images(ctx, grid, max(grid.size) * INJECT_SAMPLES)
        if scratch["fronts"]:
            _raster_pass(ctx, programs, {"MODE_FRONT": None, "MODE_ALBEDO": None}, drawn, None, grid, scratch)
    return scratch["fronts"]


def _raster_pass(ctx, programs, defines: dict, drawn: tuple, shadows, grid, scratch: dict) -> None:
    """vct/inject_raster.glsl in mode `defines` over every triangle of `drawn` = (scene, geometry, textures), into
    the scratch's accumulator (where it has one) and front-most images; lit by `shadows`' lights (None: no light,
    MODE_ALBEDO)."""
    side = max(grid.size) * INJECT_SAMPLES
    fronts = scratch["fronts"]
    sums = ALBEDO_SUMS if "MODE_ALBEDO" in defines else LIGHT_SUMS
    prog = programs.raster("vct/inject_raster.glsl", {**defines, **(shadows.defines if shadows else {}),
                                                      "ACC_CHANNELS": sums})
    bind_grid(prog, grid, 1)
    if shadows is not None:
        bind_lights(prog, shadows, unit=2, sky_stride=SKY_INJECTION_STRIDE)
    set_uniforms(prog, {"u_samples": float(INJECT_SAMPLES), "u_viewport": (float(side), float(side)),
                        "u_cover_test": bool(fronts)})
    if "acc" in scratch:
        scratch["acc"].bind_to_image(0, read=True, write=True)
    for i, t in enumerate(fronts):
        t.bind_to_image(1 + i, read=True, write=True)
    _rasterise(ctx, prog, *drawn, side)
    ctx.memory_barrier()


def face_albedo(ctx, programs, scene: Scene, geometry, textures: list, vox, scratch: dict | None = None) -> FaceAlbedo:
    """Each voxel face's albedo: the mean over the surface points whose light the injection sends through it,
    with the same weights and covered sides left out (vct/inject_raster.glsl MODE_ALBEDO, vct/face_albedo.glsl).
    Made from the geometry and the materials alone: a light edit keeps it, a colour edit re-makes it alone. The
    front-most surfaces are `scratch`'s (front_surfaces; none: made and released here)."""
    grid = vox.grid
    out = FaceAlbedo([texture3d(ctx, grid.size, zero=True, dtype="f2") for _ in range(6)], grid)
    own = scratch is None
    scratch = {} if own else scratch
    drawn = (scene, geometry, textures)
    sums = {"fronts": front_surfaces(ctx, programs, drawn, grid, scratch)}  # its own accumulator, the shared fronts
    try:
        acc = _accumulator(ctx, grid, sums, ALBEDO_SUMS)
        _raster_pass(ctx, programs, {"MODE_ALBEDO": None}, drawn, None, grid, sums)
        run_listed(ctx, _albedo_program(programs, {}, vox, acc, out), grid.size,
                   lambda: _albedo_program(programs, {"MODE_SLIVERS": None}, vox, acc, out))
    finally:
        if "acc" in sums:
            sums["acc"].release()
        if own:
            release_scratch(scratch)
    return out


def _albedo_program(programs, defines: dict, vox, acc, out: FaceAlbedo):
    """vct/face_albedo.glsl in mode `defines`, the areas, the albedo's sums and the output images bound."""
    prog = programs.compute("vct/face_albedo.glsl", {**defines, "ACC_CHANNELS": ALBEDO_SUMS})
    unit = bind_samplers(prog, "u_area", [vox.area], 0)
    bind_samplers(prog, "u_acc", [acc], unit)
    set_uniform(prog, "u_grid_size", tuple(int(n) for n in vox.grid.size))
    for i, t in enumerate(out.textures):
        t.bind_to_image(i, read=False, write=True)
    return prog


def _resolve_program(programs, defines: dict, vox, acc, shadows, grid, outputs):
    """vct/inject.glsl in mode `defines`, its volumes, lights, grid and output images bound."""
    prog = programs.compute("vct/inject.glsl", {**defines, **shadows.defines, "ACC_CHANNELS": LIGHT_SUMS})
    unit = bind_samplers(prog, "u_area", [vox.area], 0)
    unit = bind_samplers(prog, "u_normal", [vox.normal], unit)
    unit = bind_samplers(prog, "u_acc", [acc], unit)
    bind_lights(prog, shadows, unit, sky_stride=SKY_INJECTION_STRIDE)
    bind_grid(prog, grid, 1)
    for i, t in enumerate(outputs):
        t.bind_to_image(i, read=False, write=True)
    return prog


LISTED_ROOM = 4096  # entries of a resolve's first list (made again larger where more are counted)
PER_DISPATCH = 65535 * 64  # work groups of 64 over a list, at most 65535 a dispatch


def run_listed(ctx, first, size, then, room: int | None = None) -> int:
    """Dispatch `first` (bound) over `size`: it lists items on storage buffer 5 (up to u_capacity, counted on 3),
    e.g. the faces that caught no raster sample. Then run then() — a program, bound — once per listed item (u_first,
    u_count; work groups of 64) with the list on 5. Where more were counted than fit, both run again with room for
    them all (default LISTED_ROOM). Returns the count. Why two passes: run in the resolve, every lane of a SIMD group
    paid for the group's few listed items (measured, the Cornell box's 3244 fallback faces: 190 ms of resolve, 35
    without their lighting)."""
    room = LISTED_ROOM if room is None else room
    listed = ctx.buffer(reserve=16 * room)
    try:
        listed.bind_to_storage_buffer(5)
        set_uniform(first, "u_capacity", room)
        count = dispatch_counted(ctx, first, size, VOLUME_GROUP)
        if count > room:  # the first pass writes the same outputs again, and lists them all
            return run_listed(ctx, first, size, then, count)
        if count:
            prog = then()
            listed.bind_to_storage_buffer(5)
            set_uniform(prog, "u_count", count)
            for start in range(0, count, PER_DISPATCH):
                set_uniform(prog, "u_first", start)
                dispatch(prog, (min(PER_DISPATCH, count - start),), 64)
            ctx.memory_barrier()
        return count
    finally:
        listed.release()


def front_bytes(grid) -> int:
    """The front-most images' size for `grid` (0 where they would exceed COVER_TEST_BYTES and are not made)."""
    side = int(max(grid.size)) * INJECT_SAMPLES
    total = sum(side * side * 2 * int(n) * 4 for n in grid.size)
    return total if 3 * side * side * 2 * int(max(grid.size)) * 4 <= COVER_TEST_BYTES else 0


def front_images(ctx, grid, side: int) -> list:
    """Zeroed r32ui images (side, side, 2·n_axis) for x, y, z: the front-most depth per raster column, voxel layer
    and side (vct/inject_raster.glsl); none when they would exceed COVER_TEST_BYTES."""
    import moderngl

    if not front_bytes(grid):
        return []
    out = []
    for n in grid.size:
        t = ctx.texture3d((side, side, 2 * int(n)), 1, dtype="u4")
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
        zero_texture(ctx, t)
        out.append(t)
    return out


def _rasterise(ctx, prog, scene, geometry, textures, side: int) -> None:
    """Draw every triangle through `prog` into an empty side × side framebuffer (the image stores are the output)."""
    import moderngl

    layout = [(geometry.vbo, POSITION_UV, "in_position", "in_uv")] if "in_uv" in prog else \
        [(geometry.vbo, POSITION_ONLY, "in_position")]  # the front-most pass samples no texture
    vao = ctx.vertex_array(prog, layout)
    fbo = ctx.empty_framebuffer((side, side))
    try:
        fbo.use()
        fbo.viewport = (0, 0, side, side)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        draw_by_material(prog, scene, geometry, textures, vao=vao)  # material uniforms, texture unit 0
    finally:
        vao.release()
        fbo.release()


def face_flux(ctx, programs, faces: Faces) -> tuple[list, int, int]:
    """(π·cell²·Σ_voxels Σ_g α_g·L_g per RGB channel — the outgoing flux (W) the faces carry; occupied voxels;
    faces lit at their centre for want of raster samples), summed per row on the GPU (MODE_FLUX), rows here."""
    nx, ny, nz = faces.grid.size
    out = ctx.buffer(reserve=ny * nz * 32)
    try:
        prog = programs.compute("vct/mipmap.glsl", {"MODE_FLUX": None})
        unit = bind_samplers(prog, "u_src", faces.textures, 0)
        bind_samplers(prog, "u_centroid", faces.centroids or faces.textures, unit)
        set_uniform(prog, "u_has_centroids", faces.centroids is not None)
        set_uniform(prog, "u_dst_size", (int(nx), int(ny), int(nz)))
        out.bind_to_storage_buffer(0)
        dispatch(prog, (ny, nz, 1), local=8)
        ctx.memory_barrier()
        rows = np.frombuffer(out.read(), np.float32).reshape(-1, 2, 4).astype(np.float64)
    finally:
        out.release()
    flux = rows[:, 0, :3].sum(axis=0) * math.pi * faces.grid.cell ** 2
    return [float(c) for c in flux], int(round(rows[:, 0, 3].sum())), int(round(rows[:, 1, 0].sum()))
