"""Light Propagation Volumes (seeds 000, 001, 002): RSMs → VPL injection → propagation with fuzzy occlusion →
irradiance lookup. Every scale is derived, none tuned (see the shaders' comments):

- RSM texel → VPL flux Φ = albedo × irradiance × texel area (lpv_inject.glsl), so injection is independent of
  the RSM resolution;
- a VPL is the Lambertian intensity (Φ/π)·max(0, n·ω) on 2-band SH, in the cell half a cell in front of it;
- propagation conserves flux exactly in empty space (far face 0.4006696846 sr + 4 side faces 0.4234313544 sr
  = 2π/3 per neighbour); negative lobes propagate as they are unless `clamp_negative` (which adds energy);
- lookup: irradiance = SH intensity convolved with the cosine / cell².

Iterations stop adaptively once a step moves less than `epsilon` of the injected flux.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import direct
from . import light_buffers as lb
from .grid import Grid
from .scene import Scene

FAR_FACE = 0.4006696846  # solid angle of the far face of the next cell, seen from a cell centre (design.md §3)
SIDE_FACE = 0.4234313544  # each of its four side faces; FAR_FACE + 4·SIDE_FACE = 2π/3
AXES = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))
FIXED_RANGE = 2.0 ** 29  # fixed-point headroom: a cell's coefficient sum stays below 2³¹ (see flux_bound)
SH_FLUX = 2.0 * math.sqrt(math.pi)  # flux of SH coefficients c: c0·2√π


@dataclass(frozen=True)
class LpvSettings:
    resolution: int = 32  # cells along the longest axis of the (finest) grid
    cascades: int = 1  # nested grids, each twice the extent of the last
    rsm_resolution: int = 128  # texels per side of each RSM view (sun: twice that)
    max_iterations: int = 64
    epsilon: float = 1e-3  # stop when one step moved less than this fraction of the injected flux
    occlusion: bool = True  # fuzzy occlusion from the geometry volume
    clamp_negative: bool = False
    damping: bool = False  # seed 000's directional-derivative damping at lookup
    blend_cells: float = 2.0  # cascade border blend width (cells)
    bounces: int = 3  # indirect bounces (1 = light reflected once); bounces > 1 need occlusion
    lookup: str = "flux"  # "flux": absorbed face flux per area (conserves energy); "intensity": Kaplanyan's I/cell²

    def __post_init__(self):
        if not 4 <= self.resolution <= 256:
            raise ValueError(f"resolution {self.resolution} out of range 4..256")
        if not 1 <= self.cascades <= 4:
            raise ValueError(f"cascades {self.cascades} out of range 1..4")
        if self.lookup not in ("flux", "intensity"):
            raise ValueError(f"lookup must be 'flux' or 'intensity', not {self.lookup!r}")
        if self.bounces < 1 or self.max_iterations < 1 or self.rsm_resolution < 8:
            raise ValueError("bounces and max_iterations must be ≥ 1 and rsm_resolution ≥ 8")


def sh_basis(d) -> np.ndarray:
    x, y, z = d
    return np.array([0.282094792, -0.488602512 * y, 0.488602512 * z, -0.488602512 * x])


def sh_clamped_cosine(n) -> np.ndarray:
    x, y, z = n
    return np.array([0.886226925, -1.023326708 * y, 1.023326708 * z, -1.023326708 * x])


def transfer_matrices() -> tuple[np.ndarray, np.ndarray]:
    """The face scheme of lpv_propagate.glsl as linear maps, one per neighbour direction d (light travelling d):
    T_d = Σ_faces (lobe(face)/π) ⊗ Y(ω_face)·Δω_face (coefficients received), and the incident-flux row
    Σ_faces Y(ω_face)·Δω_face. Returns (6, 4, 4) and (6, 4) float32."""
    transfer = np.zeros((6, 4, 4))
    incident = np.zeros((6, 4))
    for n, d in enumerate(AXES):
        d = np.asarray(d, float)
        for f in AXES:
            f = np.asarray(f, float)
            if f @ d < -0.5:
                continue  # the face shared with the neighbour
            far = f @ d > 0.5
            w = d if far else (d + 0.5 * f) / np.linalg.norm(d + 0.5 * f)
            weight = sh_basis(w) * (FAR_FACE if far else SIDE_FACE)
            transfer[n] += np.outer(sh_clamped_cosine(f) / math.pi, weight)
            incident[n] += weight
    return transfer.astype(np.float32), incident.astype(np.float32)


@dataclass
class Volumes:
    """Three RGBA32F 3D textures (SH coefficients of red, green, blue) on one grid."""
    r: object
    g: object
    b: object

    def release(self):
        for t in (self.r, self.g, self.b):
            t.release()

    def textures(self):
        return self.r, self.g, self.b


def _volumes(ctx, grid: Grid, data: np.ndarray | None = None) -> Volumes:
    import moderngl

    size = tuple(int(v) for v in grid.size)
    texs = []
    for i in range(3):
        payload = None if data is None else np.ascontiguousarray(data[..., i, :], np.float32).tobytes()
        t = ctx.texture3d(size, 4, payload, dtype="f4")
        t.filter = (moderngl.LINEAR, moderngl.LINEAR)
        t.repeat_x = t.repeat_y = t.repeat_z = False
        texs.append(t)
    if data is None:
        for t in texs:
            t.write(np.zeros(size[::-1] + (4,), np.float32).tobytes())
    return Volumes(*texs)


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
        right, up, back = view.view_matrix[0, :3], view.view_matrix[1, :3], view.view_matrix[2, :3]
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
        del up
    return Rsm(*targets, direct.ssbo(ctx, records), size, resolution // scale, flux_bound(buffers), vao, fbo, depth)


class LpvGridState:
    """GPU state of one cascade: injection accumulator, ping-pong volumes and the accumulation volume."""

    def __init__(self, ctx, grid: Grid):
        self.grid = grid
        n = int(np.prod(grid.size))
        self.accum_ints = ctx.buffer(reserve=n * 12 * 4)
        self.injected = _volumes(ctx, grid)
        self.accum = _volumes(ctx, grid)
        self.ping = _volumes(ctx, grid)
        self.pong = _volumes(ctx, grid)
        self.injected_next = _volumes(ctx, grid)  # a bounce's source (ping/pong are the propagation buffers)
        self.counter = ctx.buffer(reserve=4)
        self.face_flux = ctx.buffer(reserve=n * 6 * 16)  # vec4 per cell and direction of travel
        self.front = self.back = None  # absorbed-light irradiance per fine voxel, last pass (set by `absorb`)
        self.front_total = self.back_total = None  # summed over bounces

    def release(self):
        for obj in (self.accum_ints, self.injected, self.accum, self.ping, self.pong, self.injected_next,
                    self.counter, self.face_flux,
                    self.front, self.back, self.front_total, self.back_total):
            if obj is not None:
                obj.release()


def _grid_uniforms(prog, grid: Grid) -> None:
    direct._set(prog, "u_grid_origin", tuple(float(c) for c in grid.origin))
    direct._set(prog, "u_grid_cell", float(grid.cell))
    direct._set(prog, "u_grid_size", tuple(int(c) for c in grid.size))


def sky_flux_bound(grid: Grid, world_color) -> float:
    """Flux the world can push through the grid's border faces: π·L_max·(border area)."""
    nx, ny, nz = grid.size
    border = 2 * (nx * ny + ny * nz + nx * nz) * grid.cell ** 2
    return math.pi * float(max(world_color[:3])) * border


def inject(ctx, programs, rsm: Rsm, shadows, state: LpvGridState, world_color=(0.0, 0.0, 0.0),
           gv=None) -> float:
    """RSM texels (and world light at the open border) → fixed-point SH sums → state.injected. Returns the
    injected flux (W, sum of RGB)."""
    grid = state.grid
    sky = max(world_color[:3]) > 0
    scale = FIXED_RANGE / (rsm.flux_bound + (sky_flux_bound(grid, world_color) if sky else 0.0))
    state.accum_ints.clear()
    prog = programs.compute("lpv_inject.glsl")
    for unit, tex in enumerate((rsm.position, rsm.normal, rsm.albedo)):
        tex.use(location=unit)
    direct._set(prog, "u_rsm_position", 0)
    direct._set(prog, "u_rsm_normal", 1)
    direct._set(prog, "u_rsm_albedo", 2)
    direct._set(prog, "u_rsm_size", rsm.size)
    direct._set(prog, "u_rsm_resolution", int(rsm.resolution))
    direct._set(prog, "u_fixed_scale", float(scale))
    _grid_uniforms(prog, grid)
    shadows.light_ssbo.bind_to_storage_buffer(0)
    shadows.view_ssbo.bind_to_storage_buffer(1)
    shadows.polygon_ssbo.bind_to_storage_buffer(2)
    rsm.views_ssbo.bind_to_storage_buffer(3)
    state.accum_ints.bind_to_storage_buffer(4)
    prog.run((rsm.size[0] + 7) // 8, (rsm.size[1] + 7) // 8, 1)
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


def resolve(ctx, programs, state: LpvGridState, scale: float, target: Volumes, add: bool = False) -> float:
    """Fixed-point sums → float volumes; returns the flux they hold (sum over RGB of |band 0|·2√π)."""
    prog = programs.compute("lpv_resolve.glsl", {"MODE_ADD": 1} if add else None)
    state.accum_ints.bind_to_storage_buffer(4)
    for unit, tex in enumerate(target.textures()):
        tex.bind_to_image(unit, read=True, write=True)
    direct._set(prog, "u_grid_size", tuple(int(c) for c in state.grid.size))
    direct._set(prog, "u_fixed_scale", float(scale))
    nx, ny, nz = state.grid.size
    prog.run((nx + 3) // 4, (ny + 3) // 4, (nz + 3) // 4)
    ints = np.frombuffer(state.accum_ints.read(), np.int32).reshape(-1, 3, 4)
    return float(np.abs(ints[:, :, 0].astype(np.float64)).sum() / scale * SH_FLUX)


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


def copy_volumes(ctx, src: Volumes, dst: Volumes) -> None:
    for a, b in zip(src.textures(), dst.textures()):
        b.write(a.read())


def inject_all(ctx, programs, rsm: Rsm, shadows, grids: list, world_color=(0.0, 0.0, 0.0),
               geometry_volumes=None) -> list:
    """Inject the RSM VPLs and the world light into a fresh state per cascade (finest first). World light enters
    each cascade through its open border: exact for the coarsest grid, whose border is the scene's; a finer
    cascade assumes the world is visible beyond its border (true outdoors, too bright inside closed rooms)."""
    states = []
    for i, grid in enumerate(grids):
        state = LpvGridState(ctx, grid)
        gv = geometry_volumes[i] if geometry_volumes else None
        state.injected_flux = inject(ctx, programs, rsm, shadows, state, world_color, gv)
        states.append(state)
    return states


def propagate_all(ctx, programs, states: list, geometry_volumes: list, settings: LpvSettings) -> dict:
    """Propagate every cascade from its injected light, then each further bounce from what the surfaces absorbed
    and reflect. Without a geometry volume there is nothing to absorb light: one bounce, intensity lookup."""
    stats = []
    for state, gv in zip(states, geometry_volumes):
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


@dataclass
class GeometryVolume:
    """Fuzzy occlusion of one cascade (seed 000 §3.4) and the surface voxels that absorb what it stops."""
    blocking: object  # RGBA32F 3D texture, LPV size + 1: channel a = blocked fraction of cell c's lower face normal to a
    fine: Grid  # surface voxels: half the LPV cell, offset by half an LPV cell
    area: object  # fine voxel textures from voxelize(): projected areas per axis + total area
    normal: object
    albedo: object

    def release(self):
        for t in (self.blocking, self.area, self.normal, self.albedo):
            t.release()


def face_blocking(area: np.ndarray, grid: Grid) -> np.ndarray:
    """Blocked fraction of every LPV face from surface voxels of half the cell size (fine grid, origin − cell/2).

    The face between cells c − e_a and c gets the blocking potential of seed 000 §3.4, B = Σ A_s·|n_s·a| / s²
    (clamped to 1), summed over the surfels inside the cell-sized box centred on that face — exactly the eight
    fine voxels [2c_a, 2c_a+2) along a and [2c_u+1, 2c_u+3) along the other axes. (A box centred on the face,
    rather than the four corner cells of the classic GV, which average over 2s × 2s and so let a 45° wall block
    only half of each face it crosses.) Returns (nz+1, ny+1, nx+1, 4), channel a at the index of cell c.
    """
    nx, ny, nz = grid.size
    out = np.zeros((nz + 1, ny + 1, nx + 1, 4), np.float64)
    s2 = grid.cell ** 2
    proj = [area[..., a] for a in range(3)]  # fine arrays indexed [z, y, x]
    # axis x: pairs [2i, 2i+2) along x, [2j+1, 2j+3) along y, [2k+1, 2k+3) along z
    px = proj[0][1:2 * nz + 1, 1:2 * ny + 1, 0:2 * nx + 2]
    out[:nz, :ny, :, 0] = px.reshape(nz, 2, ny, 2, nx + 1, 2).sum(axis=(1, 3, 5)) / s2
    py = proj[1][1:2 * nz + 1, 0:2 * ny + 2, 1:2 * nx + 1]
    out[:nz, :, :nx, 1] = py.reshape(nz, 2, ny + 1, 2, nx, 2).sum(axis=(1, 3, 5)) / s2
    pz = proj[2][0:2 * nz + 2, 1:2 * ny + 1, 1:2 * nx + 1]
    out[:, :ny, :nx, 2] = pz.reshape(nz + 1, 2, ny, 2, nx, 2).sum(axis=(1, 3, 5)) / s2
    out[..., :3] = np.minimum(out[..., :3], 1.0)
    return out.astype(np.float32)


def geometry_volumes(ctx, programs, scene: Scene, geometry, textures, grids: list) -> list:
    """Fuzzy-occlusion volumes, one per cascade, from a voxelisation of the whole scene (view-independent).

    The blocking potential of seed 000 §3.4 is evaluated in closed form at the axis directions — B_a, the fraction
    of a face normal to a that surfaces cover — instead of through a 2-band SH projection, because 2-band SH cannot
    hold a two-sided blocker (the band-1 terms of |n·ω| vanish, which would leave a full wall blocking at most half
    the light).
    """
    import moderngl

    from .voxelize import voxelize

    out = []
    for grid in grids:
        fine = Grid(tuple(np.asarray(grid.origin) - grid.cell / 2), grid.cell / 2, tuple(2 * n + 2 for n in grid.size))
        vox = voxelize(ctx, programs, scene, geometry, textures, fine)
        blocking = face_blocking(vox.read()["area"], grid)
        tex = ctx.texture3d(tuple(n + 1 for n in grid.size), 4, np.ascontiguousarray(blocking).tobytes(), dtype="f4")
        for t in (tex, vox.area, vox.normal, vox.albedo):
            t.filter = (moderngl.NEAREST, moderngl.NEAREST)
        vox.emission.release()
        out.append(GeometryVolume(tex, fine, vox.area, vox.normal, vox.albedo))
    return out


def absorb(ctx, programs, state: LpvGridState, gv: GeometryVolume, add: bool) -> None:
    """Front/back irradiance of every surface voxel from the flux occlusion stopped (lpv_absorb.glsl); `add`
    adds it to the bounce totals instead of starting them."""
    import moderngl

    size = gv.fine.size
    for name in ("front", "back", "front_total", "back_total"):
        if getattr(state, name) is None:
            t = ctx.texture3d(size, 4, dtype="f4")
            t.filter = (moderngl.NEAREST, moderngl.NEAREST)
            setattr(state, name, t)
    prog = programs.compute("lpv_absorb.glsl", {"MODE_ADD": 1} if add else None)
    state.face_flux.bind_to_storage_buffer(6)
    gv.blocking.use(location=0)
    gv.normal.use(location=1)
    gv.area.use(location=2)
    direct._set(prog, "u_geometry", 0)
    direct._set(prog, "u_voxel_normal", 1)
    direct._set(prog, "u_voxel_area", 2)
    direct._set(prog, "u_grid_size", tuple(int(c) for c in state.grid.size))
    direct._set(prog, "u_cell", float(state.grid.cell))
    for unit, name in enumerate(("front", "back", "front_total", "back_total")):
        getattr(state, name).bind_to_image(unit, read=True, write=True)
    prog.run(*((n + 3) // 4 for n in size))


def inject_bounce(ctx, programs, state: LpvGridState, gv: GeometryVolume, bound: float) -> float:
    """Re-inject the light the surfaces absorbed in the last pass, times their albedo (lpv_bounce.glsl)."""
    scale = FIXED_RANGE / max(bound, 1e-12)
    state.accum_ints.clear()
    prog = programs.compute("lpv_bounce.glsl")
    for unit, (name, tex) in enumerate((("u_front", state.front), ("u_back", state.back),
                                        ("u_voxel_normal", gv.normal), ("u_voxel_area", gv.area),
                                        ("u_voxel_albedo", gv.albedo))):
        tex.use(location=unit)
        direct._set(prog, name, unit)
    direct._set(prog, "u_fine_origin", tuple(float(c) for c in gv.fine.origin))
    direct._set(prog, "u_fine_size", tuple(gv.fine.size))
    _grid_uniforms(prog, state.grid)
    direct._set(prog, "u_fixed_scale", float(scale))
    state.accum_ints.bind_to_storage_buffer(4)
    prog.run(*((n + 3) // 4 for n in gv.fine.size))
    return resolve(ctx, programs, state, scale, state.ping)


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
