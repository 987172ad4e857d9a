"""Light Propagation Volumes (seeds 000, 001, 002): RSMs → VPL injection → propagation with fuzzy occlusion →
absorbed light → irradiance. Every scale is derived, none tuned (see the shaders' comments):

- RSM texel → VPL flux Φ = albedo × irradiance × texel area (lpv_inject.glsl), so injection is independent of
  the RSM resolution; world light enters through the grid's open border (lpv_sky.glsl);
- a VPL is the Lambertian intensity (Φ/π)·max(0, n·ω) on 2-band SH, in the cell half a cell in front of it;
- propagation conserves flux exactly in empty space (far face 0.4006696846 sr + 4 side faces 0.4234313544 sr
  = 2π/3 per neighbour); negative lobes propagate as they are unless `clamp_negative` (which adds energy);
- lookup (default "flux"): a surface's irradiance is the flux fuzzy occlusion stopped at it, per area — summed
  over all surfaces this is exactly the injected flux that did not leave the grid (lpv_occlusion.py); the
  classic lookup, SH intensity convolved with the cosine / cell², is `lookup="intensity"`;
- bounces: absorbed light × albedo is injected again;
- transport (default "gather", lpv_gather.py): every surface voxel gathers the VPLs' light directly, bounce by
  bounce, with fuzzy visibility — the face scheme turns light sideways within a few cells; "propagate" is the
  classic LPV above. World light propagates either way.

Iterations stop adaptively once a step moves less than `epsilon` of the injected flux.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import direct
from . import light_buffers as lb
from .grid import Grid
from .lpv_gather import bounce_vpls, extrapolate_tail, gather, rsm_uniforms, vpl_list
from .lpv_occlusion import GeometryVolume, absorb, geometry_volumes, inject_bounce  # noqa: F401 (pipeline: lpv.*)
from .lpv_state import (FIXED_RANGE, SH_FLUX, LpvGridState, LpvSettings, Volumes, _grid_uniforms,  # noqa: F401
                        _volumes, copy_volumes, resolve, transfer_matrices)
from .scene import Scene

def cascade_grids(scene: Scene, settings: LpvSettings) -> list[Grid]:
    """The coarsest cascade covers the scene; each finer one has half the cell size, centred on the camera
    (clamped into the scene) and snapped to whole cells so small camera moves don't shift the lattice."""
    lo, hi = scene.bounds()
    coarse = Grid.fit(lo, hi, settings.resolution, margin_cells=1)
    if settings.cascades <= 1:
        return [coarse]
    cam = np.asarray(scene.camera.matrix_world, np.float64)[:3, 3] if scene.camera is not None else (lo + hi) / 2
    centre = np.clip(cam, lo, hi)
    grids = [coarse]
    n = settings.resolution
    for level in range(1, settings.cascades):
        cell = coarse.cell / 2 ** level
        grids.append(Grid.centered(centre, cell, (n, n, n)))
    return grids[::-1]  # finest first


@dataclass
class Rsm:
    position: object
    normal: object
    albedo: object
    views_ssbo: object
    size: tuple
    resolution: int
    flux_bound: float
    vao: object = None
    fbo: object = None
    depth: object = None

    def release(self):
        for obj in (self.position, self.normal, self.albedo, self.views_ssbo, self.fbo, self.depth, self.vao):
            if obj is not None:
                obj.release()


RSM_VIEW_DTYPE = np.dtype([("params", "<f4", 4), ("origin", "<f4", 4), ("axis", "<f4", 4), ("right", "<f4", 4)])


def flux_bound(buffers: lb.LightBuffers) -> float:
    """An upper bound of the flux all lights together can deliver to surfaces (W), for the fixed-point scale."""
    total = 0.0
    for i, rec in enumerate(buffers.lights):
        color = float(np.max(rec["color_type"][:3]))
        kind = int(rec["color_type"][3])
        if kind == lb.LIGHT_SUN:
            views = [v for v, l in zip(buffers.views, buffers.view_lights) if l == i]
            half = views[0].half_extent if views else 1.0
            total += color * (2 * half) ** 2
        elif kind in (lb.LIGHT_POINT, lb.LIGHT_SPOT):
            total += color * 4 * math.pi
        else:
            first, count, two_sided = int(rec["polygon"][0]), int(rec["polygon"][1]), rec["polygon"][2] > 0.5
            p = buffers.polygon_vertices[first:first + count, :3].astype(np.float64)
            area = 0.5 * np.linalg.norm(sum(np.cross(p[j], p[(j + 1) % count]) for j in range(count)))
            total += color * math.pi * area * (2 if two_sided else 1)
    return max(total, 1e-12)


def render_rsm(ctx, programs, scene: Scene, geometry, textures, shadows, resolution: int) -> Rsm:
    """Render every shadow view of every light once more as an RSM (position, normal, albedo) into an atlas."""
    import moderngl

    buffers = shadows.buffers
    views = buffers.views
    res = [resolution * (2 if v.ortho else 1) for v in views]
    tiles, size, scale = lb.allocate_atlas(res, max_height=ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384))
    targets = [ctx.texture(size, 4, dtype="f4") for _ in range(3)]
    for t in targets:
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    depth = ctx.depth_renderbuffer(size)
    fbo = ctx.framebuffer(color_attachments=targets, depth_attachment=depth)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.disable(moderngl.CULL_FACE)
    prog = programs.raster("rsm.glsl")
    vao = ctx.vertex_array(prog, [(geometry.vbo, "3f 3f 2f 3f", "in_position", "in_normal", "in_uv", "in_geo_normal")])
    records = np.zeros(len(views), RSM_VIEW_DTYPE)
    for i, (view, (x, y, w, h)) in enumerate(zip(views, tiles)):
        fbo.viewport = (x, y, w, h)
        prog["u_view_projection"].write(view.view_projection.T.astype("f4").tobytes())
        right, back = view.view_matrix[0, :3], view.view_matrix[2, :3]  # rows of world → view: right, up, back
        direct._set(prog, "u_origin", tuple(float(c) for c in view.origin))
        direct._set(prog, "u_forward", tuple(float(c) for c in -back))
        direct._set(prog, "u_ortho", bool(view.ortho))
        direct._set(prog, "u_view_index", float(i))
        direct.draw_by_material(prog, scene, geometry, textures, vao=vao)
        light = buffers.view_lights[i]
        rec = buffers.lights[light]
        k = (i - int(rec["params"][1])) // max(int(rec["params"][3]), 1)
        records[i]["params"] = (0.0 if view.ortho else view.half_extent,
                                2 * view.half_extent / w if view.ortho else 0.0, light, k)
        records[i]["origin"] = (*view.origin, 1.0 if view.ortho else 0.0)
        records[i]["axis"] = (*-back, 0.0)
        records[i]["right"] = (*right, 0.0)
    return Rsm(*targets, direct.ssbo(ctx, records), size, resolution // scale, flux_bound(buffers), vao, fbo, depth)


def sky_flux_bound(grid: Grid, world_color) -> float:
    """Flux the world can push through the grid's border faces: π·L_max·(border area)."""
    nx, ny, nz = grid.size
    border = 2 * (nx * ny + ny * nz + nx * nz) * grid.cell ** 2
    return math.pi * float(max(world_color[:3])) * border


def inject(ctx, programs, rsm: Rsm, shadows, state: LpvGridState, world_color=(0.0, 0.0, 0.0),
           gv=None, downsample: int = 1, vpls: bool = True) -> float:
    """RSM texels (unless not `vpls`) and world light at the open border → fixed-point SH sums → state.injected.
    Returns the injected flux (W, sum of RGB)."""
    grid = state.grid
    sky = max(world_color[:3]) > 0
    scale = FIXED_RANGE / (rsm.flux_bound + (sky_flux_bound(grid, world_color) if sky else 0.0))
    state.accum_ints.clear()
    if vpls:
        prog = programs.compute("lpv_inject.glsl")
        blocks = rsm_uniforms(prog, rsm, shadows, downsample)
        direct._set(prog, "u_fixed_scale", float(scale))
        _grid_uniforms(prog, grid)
        state.accum_ints.bind_to_storage_buffer(4)
        prog.run((blocks[0] + 7) // 8, (blocks[1] + 7) // 8, 1)
    if sky:
        sky_prog = programs.compute("lpv_sky.glsl")
        _grid_uniforms(sky_prog, grid)
        direct._set(sky_prog, "u_world", tuple(float(c) for c in world_color[:3]))
        direct._set(sky_prog, "u_fixed_scale", float(scale))
        direct._set(sky_prog, "u_occlusion", gv is not None)
        if gv is not None:
            gv.blocking.use(location=0)
        direct._set(sky_prog, "u_geometry", 0)
        state.accum_ints.bind_to_storage_buffer(4)
        nx, ny, nz = grid.size
        sky_prog.run((nx + 3) // 4, (ny + 3) // 4, (nz + 3) // 4)
    return resolve(ctx, programs, state, scale, state.injected)


CHECK_EVERY = 4  # propagation steps between reads of the moved-flux counter (each read waits for the GPU)


def propagate(ctx, programs, state: LpvGridState, source: Volumes, injected_flux: float, gv_texture,
              settings: LpvSettings, accumulate: bool = True) -> dict:
    """Propagate `source` until a step moves < ε of the injected flux (checked every CHECK_EVERY steps);
    with `accumulate`, add every step to state.accum (needed by the intensity lookup only)."""
    prog = programs.compute("lpv_propagate.glsl", {"MODE_ACCUMULATE": 1} if accumulate else None)
    nx, ny, nz = state.grid.size
    flux_scale = FIXED_RANGE / max(injected_flux, 1e-12) / 4  # moved flux never exceeds the injected flux
    direct._set(prog, "u_grid_size", (int(nx), int(ny), int(nz)))
    direct._set(prog, "u_occlusion", bool(settings.occlusion and gv_texture is not None))
    direct._set(prog, "u_clamp_negative", bool(settings.clamp_negative))
    direct._set(prog, "u_flux_scale", float(flux_scale))
    transfer, incident = transfer_matrices()
    if "u_transfer" in prog:
        # GLSL mat4 is column-major: pass each matrix transposed.
        prog["u_transfer"].write(np.ascontiguousarray(transfer.transpose(0, 2, 1)).tobytes())
        prog["u_incident"].write(incident.tobytes())
    if gv_texture is not None:
        gv_texture.use(location=3)
    direct._set(prog, "u_geometry", 3)
    src, dst = source, state.ping
    state.face_flux.clear()
    state.face_flux.bind_to_storage_buffer(6)
    moved_history = []
    for step in range(settings.max_iterations):
        for unit, (name, tex) in enumerate(zip(("u_src_r", "u_src_g", "u_src_b"), src.textures())):
            tex.use(location=unit)
            direct._set(prog, name, unit)
        for unit, tex in enumerate(dst.textures()):
            tex.bind_to_image(unit, read=False, write=True)
        for unit, tex in enumerate(state.accum.textures()):
            tex.bind_to_image(3 + unit, read=True, write=True)
        check = (step + 1) % CHECK_EVERY == 0 or step + 1 == settings.max_iterations
        if check:
            state.counter.write(np.zeros(1, np.int32).tobytes())
        state.counter.bind_to_storage_buffer(5)
        prog.run((nx + 3) // 4, (ny + 3) // 4, (nz + 3) // 4)
        src, dst = dst, (state.pong if dst is state.ping else state.ping)
        if check:
            moved = int(np.frombuffer(state.counter.read(), np.int32)[0]) / flux_scale
            moved_history.append(moved)
            if moved < settings.epsilon * injected_flux:
                break
    state.last = src
    return {"iterations": step + 1, "moved": moved_history}


def inject_all(ctx, programs, rsm: Rsm, shadows, grids: list, world_color=(0.0, 0.0, 0.0),
               gvs=None, downsample: int = 1, gather_vpls: int = 0) -> list:
    """Inject the RSM VPLs and the world light into a fresh state per cascade (finest first). World light enters
    each cascade through its open border: exact for the coarsest grid, whose border is the scene's; a finer
    cascade assumes the world is visible beyond its border (true outdoors, too bright inside closed rooms).
    With `gather_vpls` > 0 the VPLs are listed for the gathered first bounce (state.vpls) instead of injected."""
    states = []
    for i, grid in enumerate(grids):
        state = LpvGridState(ctx, grid)
        gv = gvs[i] if gvs else None
        state.injected_flux = inject(ctx, programs, rsm, shadows, state, world_color, gv, downsample,
                                     vpls=not gather_vpls)
        if gather_vpls:
            state.vpls = vpl_list(ctx, programs, rsm, shadows, grid, gather_vpls)
        states.append(state)
    return states


def propagate_all(ctx, programs, states: list, gvs: list, settings: LpvSettings) -> dict:
    """Propagate every cascade from its injected light, then each further bounce from what the surfaces absorbed
    and reflect. Without a geometry volume there is nothing to absorb light: one bounce, intensity lookup."""
    stats = []
    for state, gv in zip(states, gvs):
        copy_volumes(ctx, state.injected, state.accum)  # the injected light itself lights nearby surfaces
        state.face_flux.clear()
        if gv is not None:
            absorb(ctx, programs, state, gv, add=False)  # zeros, should no light reach this cascade
        bounces = []
        source, flux = state.injected, state.injected_flux
        for bounce in range(max(1, settings.bounces) if gv is not None else 1):
            if flux <= 0:
                break
            info = propagate(ctx, programs, state, source, flux, gv.blocking if gv is not None else None, settings,
                             accumulate=gv is None or settings.lookup == "intensity")
            bounces.append({"injected_flux": flux, "iterations": info["iterations"],
                            "moved_last": info["moved"][-1] if info["moved"] else 0.0})
            if gv is None:
                break
            absorb(ctx, programs, state, gv, add=bounce > 0)
            if bounce + 1 < settings.bounces:
                flux = inject_bounce(ctx, programs, state, gv, bound=flux)
                copy_volumes(ctx, state.ping, state.injected_next)
                source = state.injected_next
        stats.append({"cells": list(state.grid.size), "cell": state.grid.cell,
                      "injected_flux": state.injected_flux, "bounces": bounces,
                      "iterations": sum(b["iterations"] for b in bounces)})
    return {"cascades": stats}


def gather_all(ctx, programs, states: list, gvs: list, settings: LpvSettings) -> dict:
    """The gathered transport (lpv_gather.py), per cascade: world light propagates and is absorbed as in
    `propagate_all`; the RSM's VPLs (state.vpls) and then, bounce by bounce, the light the surface voxels reflect
    are gathered straight to the surface voxels."""
    stats = []
    for state, gv in zip(states, gvs):
        state.face_flux.clear()
        iterations = 0
        if state.injected_flux > 0:  # world light: the only light injected for this transport
            iterations = propagate(ctx, programs, state, state.injected, state.injected_flux, gv.blocking, settings,
                                   accumulate=False)["iterations"]
        absorb(ctx, programs, state, gv, add=False)  # the world light's irradiance (zeros without it)
        bounces = []
        gathered = min(settings.bounces, settings.gathered_bounces or settings.bounces)
        vpls = state.vpls
        for bounce in range(gathered):
            gather(ctx, programs, state, gv, vpls, settings.occlusion, fresh=bounce > 0)
            bounces.append({"vpls": vpls.count, "flux": vpls.flux, "block": vpls.block})
            if bounce > 0:
                vpls.release()
            if vpls.count == 0 or bounce + 1 == settings.bounces:
                break
            previous = vpls.flux_rgb
            vpls = bounce_vpls(ctx, programs, state, gv, settings.gather_vpls)
            if bounce + 1 == gathered:  # bounces gathered + 1 … N: extrapolated from the flux ratio
                vpls.release()
                with np.errstate(divide="ignore", invalid="ignore"):
                    ratio = np.nan_to_num(np.asarray(vpls.flux_rgb) / np.asarray(previous))
                ratio = np.clip(ratio, 0.0, 0.99)  # < 1: a passive scene cannot gain light per bounce
                n = settings.bounces - gathered
                tail = ratio * (1.0 - ratio ** n) / (1.0 - ratio)
                extrapolate_tail(ctx, programs, state, gv, tail)
                bounces.append({"extrapolated": n, "ratio": [float(r) for r in ratio]})
        stats.append({"cells": list(state.grid.size), "cell": state.grid.cell,
                      "injected_flux": state.injected_flux + state.vpls.flux, "world_flux": state.injected_flux,
                      "bounces": bounces, "iterations": iterations})
    return {"cascades": stats}


def lighting(ctx, programs, gbuffer, states: list, gvs: list, settings: LpvSettings):
    """Diffuse Indirect (irradiance/π) per G-buffer pixel from the accumulated volumes (RGBA32F texture)."""
    w, h = gbuffer.size
    out = ctx.texture((w, h), 4, dtype="f4")
    flux_mode = settings.lookup == "flux" and all(g is not None for g in gvs)
    prog = programs.compute("lpv_lighting.glsl", {"MODE_FLUX": 1} if flux_mode else None)
    out.bind_to_image(0, read=False, write=True)
    gbuffer.textures["position"].use(location=0)
    gbuffer.textures["normal"].use(location=1)
    direct._set(prog, "u_position", 0)
    direct._set(prog, "u_normal", 1)
    unit = 2
    n = len(states)
    per_cascade = {f"u_accum_{c}": [s.accum.textures()[i] for s in states] for i, c in enumerate("rgb")}
    if flux_mode:
        per_cascade = {"u_front": [s.front_total for s in states], "u_back": [s.back_total for s in states],
                       "u_voxel_normal": [g.normal for g in gvs]}
        fine_origin = [tuple(float(c) for c in g.fine.origin) for g in gvs]
        direct._set(prog, "u_fine_origin", fine_origin + [fine_origin[-1]] * (4 - n))
        direct._set(prog, "u_fine_size", [tuple(g.fine.size) for g in gvs] + [(1, 1, 1)] * (4 - n))
    for name, texs in per_cascade.items():
        units = []
        for tex in texs:
            tex.use(location=unit)
            units.append(unit)
            unit += 1
        units += [units[-1]] * (4 - n)
        direct._set(prog, name, units)
    origins = [tuple(float(c) for c in s.grid.origin) for s in states]
    direct._set(prog, "u_origin", origins + [origins[-1]] * (4 - n))
    direct._set(prog, "u_cell", [float(s.grid.cell) for s in states] + [1.0] * (4 - n))
    direct._set(prog, "u_size", [tuple(int(c) for c in s.grid.size) for s in states] + [(1, 1, 1)] * (4 - n))
    direct._set(prog, "u_cascades", n)
    direct._set(prog, "u_blend_cells", float(settings.blend_cells))
    direct._set(prog, "u_damping", bool(settings.damping))
    direct._set(prog, "u_image_size", (w, h))
    prog.run((w + 7) // 8, (h + 7) // 8, 1)
    return out


def step_fluxes(ctx, programs, grid: Grid, initial: np.ndarray, steps: int, settings: LpvSettings,
                blocking=None) -> list:
    """Diagnostics: propagate SH volumes `initial` ((nz, ny, nx, 3, 4): RGB × 4 coefficients) for `steps` steps
    with the real shaders and return the signed flux (RGB) each step leaves in the grid: Σ c0·2√π per channel."""
    state = LpvGridState(ctx, grid)
    try:
        source = _volumes(ctx, grid, initial)
        fluxes = []
        src = source
        one = LpvSettings(**{**settings.__dict__, "max_iterations": 1, "epsilon": 0.0})
        for _ in range(steps):
            propagate(ctx, programs, state, src, 1.0, blocking, one)
            out = state.last
            data = np.stack([np.frombuffer(t.read(), np.float32).reshape(grid.shape_zyx + (4,))
                             for t in out.textures()], axis=-2)
            fluxes.append(data[..., 0].astype(np.float64).sum(axis=(0, 1, 2)) * SH_FLUX)
            src = _volumes(ctx, grid, data)  # copy out of ping before the next step overwrites it
        return fluxes
    finally:
        state.release()
