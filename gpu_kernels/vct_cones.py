"""VCT cone passes (seed 004 §4.5.2): the gathers at voxel faces (vct_bounce) and at G-buffer pixels (vct_trace),
plus readbacks for tests and statistics. Data types, settings and the injection / mipmap passes are in vct.py."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from . import direct
from .grid import Grid
from .vct import MAX_CONES, ConeVolumes, Faces, VctSettings, _dispatch, _grid_uniforms, _texture3d, _units, \
    _volume_units, build_volumes, cone_table, face_flux, subray_radius


def _cone_uniforms(prog, grid: Grid, levels: int, s: VctSettings, world) -> None:
    """Grid, cone table and trace settings of vct_common.glsl."""
    dirs, weights, tans = cone_table(s.diffuse_cones, s.diffuse_aperture)
    n = len(weights)
    cones = np.zeros((MAX_CONES, 4), np.float32)
    cones[:n, :3], cones[:n, 3] = dirs, weights
    tan = np.zeros(MAX_CONES, np.float32)
    tan[:n] = tans
    if "u_cones" in prog:
        prog["u_cones"].write(cones.tobytes())
    if "u_cone_tan" in prog:
        prog["u_cone_tan"].write(tan.tobytes())
    _grid_uniforms(prog, grid, levels)
    for name, value in (("u_cone_count", n), ("u_step", float(s.step_multiplier)),
                        ("u_offset", float(s.start_offset)), ("u_max_distance", float(s.max_distance)),
                        ("u_ao_distance", float(s.ao_distance)), ("u_world", tuple(float(c) for c in world[:3]))):
        direct._set(prog, name, value)


def bounce(ctx, programs, vox, direct_faces: Faces, volumes: ConeVolumes, s: VctSettings, world) -> ConeVolumes:
    """bounces − 1 gathers at the voxel faces (vct_bounce.glsl), each followed by a re-mip. Returns the volumes
    the final gather reads (a non-owning view of `volumes` when bounces = 1); `bounce_stats` lists the flux the
    faces carry after each bounce (bounce 1 = direct light reflected once)."""
    stats = [{"bounce": 1, "flux": direct_faces.flux}]
    gathered = s.bounces if not s.gathered_bounces else min(s.gathered_bounces, s.bounces)
    if gathered <= 1:
        return ConeVolumes(volumes.textures, volumes.grid, volumes.levels, volumes.anisotropic, owned=False,
                           bounce_stats=stats, layers=volumes.layers, layers_owned=False)
    grid = direct_faces.grid
    faces = Faces([_texture3d(ctx, grid.size, zero=True) for _ in range(6)], grid, direct_faces.levels)
    prog = programs.compute("vct_bounce.glsl", {"MODE_ANISO": None} if volumes.anisotropic else None)
    own, source, previous = None, volumes, None
    for b in range(2, gathered + 1):
        if b == gathered and gathered < s.bounces:  # the tail needs the last increment L_K − L_(K−1): keep L_(K−1)
            previous = faces if b > 2 else direct_faces
            if b > 2:
                faces = Faces([_texture3d(ctx, grid.size, zero=True) for _ in range(6)], grid, direct_faces.levels)
        unit = _volume_units(prog, source, 0)
        unit = _units(prog, "u_direct", direct_faces.textures, unit)
        unit = _units(prog, "u_centroid", direct_faces.centroids, unit)
        _units(prog, "u_albedo", [vox.albedo], unit)
        _cone_uniforms(prog, grid, volumes.levels, replace(s, diffuse_cones=s.bounce_cones or s.diffuse_cones), world)
        for i, t in enumerate(faces.textures):
            t.bind_to_image(i, read=False, write=True)
        _dispatch(prog, grid.size)
        ctx.memory_barrier()
        own = source = build_volumes(ctx, programs, faces, volumes.anisotropic, into=own, layers=volumes.layers)
        stats.append({"bounce": b, "flux": face_flux(ctx, programs, faces)[0]})
    if previous is not None:
        stats.append(_extrapolate_tail(ctx, programs, faces, previous, stats, s.bounces))
        if previous is not direct_faces:
            previous.release()
        own = build_volumes(ctx, programs, faces, volumes.anisotropic, into=own, layers=volumes.layers)
    own.faces, own.bounce_stats = faces, stats
    return own


def _extrapolate_tail(ctx, programs, faces: Faces, previous: Faces, stats: list, bounces: int) -> dict:
    """Bounces K+1 … N without gathering them: the light added by successive bounces of a Jacobi (power) iteration
    tends to a fixed shape that shrinks by a fixed ratio r per bounce (the dominant eigenvalue of the transport —
    in a white furnace of albedo ρ, exactly r = ρ). So with B_k the flux bounce k added (B_1 = the direct light's
    reflection) and r = B_K / B_(K−1) per RGB channel, the faces get
        L_N = L_K + (L_K − L_(K−1)) · Σ_{j=1}^{N−K} r^j
    — the increment's own spatial shape, summed as a geometric series up to the requested bounce count (truncated
    like Cycles' bounce limit, not to infinity), in place on the GPU (vct_bounce_tail.glsl). Coverage α is kept.
    Returns the statistics row of the tail."""
    k = len(stats)  # bounces gathered so far (stats[i] = after bounce i + 1)
    flux = [np.asarray(st["flux"], np.float64) for st in stats]
    added = [flux[0]] + [flux[i] - flux[i - 1] for i in range(1, k)]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(added[-2] > 0, added[-1] / added[-2], 0.0)
    ratio = np.clip(np.nan_to_num(ratio), 0.0, 0.99)  # < 1: a passive scene cannot gain light per bounce
    n = bounces - k
    tail = ratio * (1.0 - ratio ** n) / (1.0 - ratio)
    prog = programs.compute("vct_bounce_tail.glsl")
    direct._set(prog, "u_grid_size", tuple(int(v) for v in faces.grid.size))
    direct._set(prog, "u_tail", tuple(float(v) for v in tail))
    for current, prev in zip(faces.textures, previous.textures):
        _units(prog, "u_previous", [prev], 0)
        current.bind_to_image(0, read=True, write=True)
        _dispatch(prog, faces.grid.size)
        ctx.memory_barrier()
    return {"bounce": bounces, "flux": [float(f) for f in flux[-1] + added[-1] * tail], "extrapolated": True,
            "ratio": [float(r) for r in ratio]}


def trace(ctx, programs, gbuffer, faces: Faces, volumes: ConeVolumes, s: VctSettings, world,
          rotation_deg: float | None = None) -> dict:
    """Diffuse cones per G-buffer pixel, or per indirect_scale² block (vct_trace.glsl): {'indirect': RGBA32F
    texture of ceil(W/s) × ceil(H/s), rgb = Diffuse Indirect (irradiance/π), a = voxel AO; 'scale': s}. The cone
    set is turned by `rotation_deg` about the normal (default s.cone_rotation)."""
    scale = int(s.indirect_scale)
    fw, fh = gbuffer.size
    w, h = -(-fw // scale), -(-fh // scale)
    out = ctx.texture((w, h), 4, dtype="f4")
    prog = _trace_program(programs, gbuffer, faces, volumes, s, world, rotation_deg, fixup=False)
    direct._set(prog, "u_image_size", (w, h))
    direct._set(prog, "u_scale", scale)
    out.bind_to_image(0, read=False, write=True)
    prog.run((w + 7) // 8, (h + 7) // 8, 1)
    ctx.memory_barrier()
    return {"indirect": out, "scale": scale}


def fixup(ctx, programs, gbuffer, faces: Faces, volumes: ConeVolumes, s: VctSettings, world, texture,
          rotation_deg: float | None = None) -> None:
    """Trace, in place and at full resolution, the pixels of `texture` that vct_upsample.glsl marked (a < 0)."""
    w, h = gbuffer.size
    prog = _trace_program(programs, gbuffer, faces, volumes, s, world, rotation_deg, fixup=True)
    direct._set(prog, "u_image_size", (w, h))
    direct._set(prog, "u_scale", 1)
    texture.bind_to_image(0, read=True, write=True)
    prog.run((w + 7) // 8, (h + 7) // 8, 1)
    ctx.memory_barrier()


def _trace_program(programs, gbuffer, faces, volumes, s, world, rotation_deg, fixup: bool):
    # Anisotropic volumes carry the layer volume the sub-rays need to find where surfaces lie (vct_crossing.glsl).
    defines = {"MODE_ANISO": None, "MODE_CROSSING": None, "SUBRAYS": int(s.subrays)} if volumes.anisotropic else {}
    if fixup:
        defines["MODE_FIXUP"] = None
    prog = programs.compute("vct_trace.glsl", defines or None)
    unit = _volume_units(prog, volumes, 0)
    unit = _units(prog, "u_centroid", faces.centroids, unit)
    for name in ("position", "normal", "geo_normal"):
        unit = _units(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    _cone_uniforms(prog, volumes.grid, volumes.levels, s, world)
    if volumes.anisotropic:
        direct._set(prog, "u_subray_radius", subray_radius(s.subrays))
    phi = math.radians(s.cone_rotation if rotation_deg is None else rotation_deg)
    direct._set(prog, "u_rotation", (math.cos(phi), math.sin(phi)))
    direct._set(prog, "u_full_size", tuple(int(n) for n in gbuffer.size))
    return prog


def read_ao(texture) -> np.ndarray:
    """Voxel AO (H, W) from vct_trace's texture, rows top-to-bottom."""
    return direct.read_texture(texture, 4)[..., 3]


def read_level(ctx, programs, texture, grid: Grid, level: int) -> np.ndarray:
    """One mip level of a volume texture as (nz, ny, nx, 4) float32 (vct_mipmap.glsl MODE_READ)."""
    nx, ny, nz = (int(n) >> level for n in grid.size)
    out = ctx.buffer(reserve=nx * ny * nz * 16)
    try:
        prog = programs.compute("vct_mipmap.glsl", {"MODE_READ": None})
        _units(prog, "u_src", [texture], 0)
        direct._set(prog, "u_dst_size", (nx, ny, nz))
        direct._set(prog, "u_level", level)
        out.bind_to_storage_buffer(0)
        _dispatch(prog, (nx, ny, nz))
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
