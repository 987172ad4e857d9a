# SPDX-License-Identifier: GPL-3.0-or-later
"""vct_trace: the diffuse cones per G-buffer pixel (or per indirect_scale² block) → Diffuse Indirect and voxel
AO (Crassin et al. 2011, cone tracing of the filtered volumes), the trace of the texels the upsampling and the
reuse after a camera move mark, the cone uniforms every cone pass shares, and read-backs for tests and statistics."""
from __future__ import annotations

import math

import numpy as np

from ..common.grid import Grid
from ..gl.bind import bind_grid, bind_samplers, dispatch, read_texture, set_uniform, set_uniforms, write_uniform
from . import replay
from .cones import MAX_CONES, cone_table, subray_radius
from .settings import VctSettings, traced_texels
from .volumes import ConeVolumes, Faces, bind_volumes


def bind_cones(prog, grid: Grid, levels: int, s: VctSettings) -> None:
    """Grid, cone table and trace settings of vct/common.glsl."""
    dirs, weights, tans = cone_table(s.diffuse_cones, s.diffuse_aperture)
    n = len(weights)
    cones = np.zeros((MAX_CONES, 4), np.float32)
    cones[:n, :3], cones[:n, 3] = dirs, weights
    tan = np.zeros(MAX_CONES, np.float32)
    tan[:n] = tans
    write_uniform(prog, "u_cones", cones)
    write_uniform(prog, "u_cone_tan", tan)
    bind_grid(prog, grid, levels)
    set_uniforms(prog, {"u_cone_count": n, "u_step": float(s.step_multiplier), "u_offset": float(s.start_offset),
                        "u_max_distance": float(s.max_distance), "u_ao_distance": float(s.ao_distance)})


def traced_size(gbuffer, s: VctSettings) -> tuple:
    """The texels vct_trace gathers at for this G-buffer (settings.traced_texels)."""
    return traced_texels(*gbuffer.size, s)


def trace(ctx, programs, gbuffer, faces: Faces, volumes: ConeVolumes, s: VctSettings,
          rotation_deg: float | None = None, hits: replay.HitPool | None = None, out=None) -> dict:
    """Diffuse cones per G-buffer pixel, or per indirect_scale² block (vct/trace.glsl): {'indirect': RGBA32F
    texture of ceil(W/s) × ceil(H/s) (`out` where given), rgb = Diffuse Indirect (irradiance/π), a = voxel AO;
    'scale': s}. The cone set is turned by `rotation_deg` about the normal (default s.cone_rotation). `hits`
    (anisotropic volumes only, vct/replay.py): an empty pool is filled with the trace's hits, a filled one replayed
    (the same image)."""
    scale = int(s.indirect_scale)
    w, h = traced_size(gbuffer, s)
    out = ctx.texture((w, h), 4, dtype="f4") if out is None else out
    mode = None if hits is None else ("replay" if hits.recorded else "record")
    prog = trace_program(programs, gbuffer, faces, volumes, s, rotation_deg, marked=False, hits=mode)
    set_uniform(prog, "u_image_size", (w, h))
    set_uniform(prog, "u_scale", scale)
    out.bind_to_image(0, read=False, write=True)
    with replay.pooled(ctx, prog, hits):
        dispatch(prog, (w, h), local=8)
        ctx.memory_barrier()
    return {"indirect": out, "scale": scale, "replayed": mode == "replay"}


MARKED_ROW = 64  # listed texels per row of trace_marked's dispatch (eight SIMD groups of eight on llvmpipe)


def marked_list(ctx, size: tuple):
    """A storage buffer for the texels a pass marks for trace_marked: an ivec2 each, room for every texel of `size`
    (vct/upsample.glsl and vct/reuse.glsl list them on binding 5)."""
    return ctx.buffer(reserve=8 * max(int(size[0]) * int(size[1]), 1))


def trace_marked(ctx, programs, gbuffer, faces: Faces, volumes: ConeVolumes, s: VctSettings, texture, scale: int,
                 listed, count: int, rotation_deg: float | None = None) -> None:
    """Trace, in place, the `count` texels of `texture` listed in `listed` (marked_list; vct/trace.glsl
    MODE_MARKED), one per invocation: at full resolution (`scale` 1) the pixels vct/upsample.glsl marked, at
    indirect_scale the texels vct/reuse.glsl found no gather of the last view for."""
    if count <= 0:
        return
    prog = trace_program(programs, gbuffer, faces, volumes, s, rotation_deg, marked=True)
    set_uniforms(prog, {"u_image_size": tuple(texture.size), "u_scale": int(scale), "u_marked": int(count),
                        "u_list_width": MARKED_ROW})
    texture.bind_to_image(0, read=False, write=True)
    listed.bind_to_storage_buffer(5)
    dispatch(prog, (MARKED_ROW, -(-int(count) // MARKED_ROW)), local=8)
    ctx.memory_barrier()


def trace_program(programs, gbuffer, faces, volumes, s, rotation_deg, marked: bool, hits: str | None = None):
    # Anisotropic volumes carry the layer volume the sub-rays need to find where surfaces lie (vct/crossing.glsl).
    defines = {"MODE_ANISO": None, "MODE_CROSSING": None, "SUBRAYS": int(s.subrays)} if volumes.anisotropic else {}
    if marked:
        defines["MODE_MARKED"] = None
    if hits is not None:  # vct/hits.glsl
        defines["MODE_RECORD" if hits == "record" else "MODE_REPLAY"] = None
    prog = programs.compute("vct/trace.glsl", defines or None)
    unit = bind_volumes(prog, volumes, 0)
    unit = bind_samplers(prog, "u_centroid", faces.centroids, unit)
    for name in ("position", "normal", "geo_normal"):
        unit = bind_samplers(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    bind_cones(prog, volumes.grid, volumes.levels, s)
    if volumes.anisotropic:
        set_uniform(prog, "u_subray_radius", subray_radius(s.subrays))
    phi = math.radians(s.cone_rotation if rotation_deg is None else rotation_deg)
    set_uniform(prog, "u_rotation", (math.cos(phi), math.sin(phi)))
    set_uniform(prog, "u_full_size", tuple(int(n) for n in gbuffer.size))
    return prog


def read_ao(texture) -> np.ndarray:
    """Voxel AO (H, W) from vct_trace's texture, rows top-to-bottom."""
    return read_texture(texture, 4)[..., 3]


def read_level(ctx, programs, texture, grid: Grid, level: int) -> np.ndarray:
    """One mip level of a volume texture as (nz, ny, nx, 4) float32 (vct/mipmap.glsl MODE_READ)."""
    nx, ny, nz = (int(n) >> level for n in grid.size)
    out = ctx.buffer(reserve=nx * ny * nz * 16)
    try:
        prog = programs.compute("vct/mipmap.glsl", {"MODE_READ": None})
        bind_samplers(prog, "u_src", [texture], 0)
        set_uniform(prog, "u_dst_size", (nx, ny, nz))
        set_uniform(prog, "u_level", level)
        out.bind_to_storage_buffer(0)
        dispatch(prog, (nx, ny, nz))
        ctx.memory_barrier()
        return np.frombuffer(out.read(), np.float32).reshape(nz, ny, nx, 4).copy()
    finally:
        out.release()


def render_info(faces: Faces, volumes: ConeVolumes, s: VctSettings) -> dict:
    """RenderResult.info for method 'vct': grid, levels, occupancy, flux per bounce."""
    g = faces.grid
    return {"grid": list(g.size), "cell": g.cell, "origin": list(g.origin), "levels": faces.levels,
            "anisotropic": s.anisotropic, "occupied_voxels": faces.occupied, "faces_without_samples": faces.missed,
            "cones": s.diffuse_cones,
            "bounces": [dict(b) for b in (volumes.bounce_stats or [])]}
