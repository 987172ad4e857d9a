# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV fuzzy occlusion and the light it stops (Elvek 2012, §3.4): the geometry volume, built from a voxelisation of
the whole scene, blocks light at cell faces; the flux it blocks is the light the surfaces there absorb, which
gives their irradiance (lpv/absorb.glsl) and, times albedo, the next bounce's VPLs (lpv/bounce.glsl).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..common.grid import Grid
from ..gl.bind import bind_grid, bind_images, bind_named, dispatch, set_uniform
from ..scene import Scene
from .crossings import crossing_layers, volume_fields
from .state import FIXED_RANGE, LpvGridState, resolve

@dataclass
class GeometryVolume:
    """Fuzzy occlusion of one cascade (Elvek 2012, §3.4) and the surface voxels that absorb what it stops."""
    blocking: object  # RGBA32F 3D texture, LPV size + 1: channel a = blocked fraction of cell c's lower face normal to a
    fine: Grid  # surface voxels: half the LPV cell, offset by half an LPV cell
    area: object  # fine voxel textures from voxelize(): projected areas per axis + total area
    normal: object
    albedo: object
    coverage: object = None  # per LPV cell (lpv/crossings.py): its surfaces' plane(s) and covered fraction
    layers: object = None  # per LPV cell: where those planes lie (cells from the grid origin)
    surfaces: object = None  # storage buffer: (x, y, z, 0) int32 of every fine voxel holding a surface
    surface_count: int = 0
    cells: np.ndarray | None = None  # (R, 3) xyz of those voxels, in the buffer's order
    surface_normal: np.ndarray | None = None  # (R, 3) their mean normals (not renormalised)
    surface_area: np.ndarray | None = None  # (R,) their surface areas (m²)
    # (2, R, 3) their front and back side's albedo (voxelize sides=True: a rug's colour on the side it covers a
    # floor from), from the materials they were voxelised with
    surface_albedo: np.ndarray | None = None
    albedo_back: object = None  # the back side's albedo texture (None: `albedo` serves both sides)
    front: object = None  # the voxelisation's front-most image, kept for material edits (up to KEEP_FRONT_BYTES)
    # Receivers per dominant axis (lpv/receivers.py, the cached transport's): each surface voxel's surfaces split
    # by axis, so a voxel may hold up to three receivers — cells, surface_normal, surface_area and surface_albedo
    # are then per receiver, and area / normal / albedo (the per-voxel textures) are None.
    axis: np.ndarray | None = None  # (R,) the dominant axis of each receiver's surfaces
    positions: np.ndarray | None = None  # (R, 3) their area-weighted centroid (m)
    bounds: tuple | None = None  # ((R, 3), (R, 3)) the box their surfaces span (m)
    receivers: object = None  # storage buffer: (R, 4) vec4 each receiver's mean normal and area (m²), centroid, box
    light_volumes: object = None  # receivers.LightVolumes: their irradiance per axis and side, for the lookup
    receiver_index: object = None  # r32i fine voxel texture: 8 × first receiver + mask of its axes (receivers.py),
    # where the grid is too large for light_volumes

    # the crossing_layers arrays the coverage / layers / layers_far textures hold, kept on the host where a transfer
    # update compares them with the next geometry's (lpv/transfer_update.changed_cells)
    crossings: dict | None = None
    layers_far: object = None  # per LPV cell (lpv/crossings.py): the far layers where its surfaces form two
    # Material edits without a voxelisation (lpv/receivers.current_albedo): the materials surface_albedo was made
    # with (receivers.albedo_signature) and, per material index, the (2, R) share of each receiver side it covers
    materials_key: str | None = None
    material_signature: list | None = None
    material_weights: dict = field(default_factory=dict)
    voxels: object = None  # regional.KeptVoxels: the receivers' voxelisation, for an object's move to update
    voxelised: float = 1.0  # the share of the fine grid voxelised to make it (less after an object's move)

    def release(self):
        for t in (self.blocking, self.area, self.normal, self.albedo, self.coverage, self.layers, self.surfaces,
                  self.albedo_back, self.front, self.receivers, self.light_volumes, self.receiver_index,
                  self.layers_far):
            if t is not None:
                t.release()


def fine_grid(grid: Grid) -> Grid:
    """The surface voxels of an LPV grid: half its cell, offset by half a cell, two more per axis."""
    return Grid(tuple(np.asarray(grid.origin) - grid.cell / 2), grid.cell / 2, tuple(2 * n + 2 for n in grid.size))


def face_blocking(area: np.ndarray, grid: Grid) -> np.ndarray:
    """Blocked fraction of every LPV face from surface voxels of half the cell size (fine grid, origin − cell/2).

    The face between cells c − e_a and c gets the blocking potential of Elvek 2012, §3.4, B = Σ A_s·|n_s·a| / s²
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


# The voxelisation's front-most image (voxel/voxelize.py sides=True) is kept with a cascade's geometry volume up to
# this size (28 MB at the default 32³), so a material edit re-voxelises the albedo without rasterising it again.
KEEP_FRONT_BYTES = 64 * 2 ** 20
def layer_area(area: np.ndarray, normals: np.ndarray, cell: float, span: np.ndarray | None = None) -> np.ndarray:
    """The surface area (R,) a voxel of side `cell` presents to light, at most one layer's: the largest section of
    the voxel across its mean normal n, cell² / max|n_i| — or, given the box its surfaces span (`span`, (R, 3) its
    sides in m), the section of that box across n's dominant axis, so that a surface that covers part of its voxel
    (a floor beside a wall) is bounded by the part it covers. Two surfaces stacked within a voxel — a rug 1 mm over
    a floor, a duplicated face — receive and reflect as one (the covered one is in its shadow); their summed area
    made the LPV reflect them twice (a coplanar duplicate face 10% brighter)."""
    unit = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
    section = np.full(len(area), cell * cell)
    if span is not None:
        a = np.abs(unit).argmax(axis=1)
        rows = np.arange(len(area))
        section = np.minimum(section, span[rows, (a + 1) % 3] * span[rows, (a + 2) % 3])
    return np.minimum(area, section / np.maximum(np.abs(unit).max(axis=1), 1e-30))


def geometry_volumes(ctx, programs, scene: Scene, geometry, textures, grids: list) -> list:
    """Fuzzy-occlusion volumes, one per cascade, from a voxelisation of the whole scene (view-independent).

    The blocking potential of Elvek 2012, §3.4 is evaluated in closed form at the axis directions — B_a, the fraction
    of a face normal to a that surfaces cover — instead of through a 2-band SH projection, because 2-band SH cannot
    hold a two-sided blocker (the band-1 terms of |n·ω| vanish, which would leave a full wall blocking at most half
    the light).
    """
    import moderngl

    from ..voxel.voxelize import front_bytes, voxelize

    out = []
    for grid in grids:
        fine = fine_grid(grid)
        keep = front_bytes(fine, 2) <= KEEP_FRONT_BYTES
        vox = voxelize(ctx, programs, scene, geometry, textures, fine, sides=True, keep_front=keep)
        arrays = vox.read()
        area = arrays["area"]
        blocking = face_blocking(area, grid)
        tex = ctx.texture3d(tuple(n + 1 for n in grid.size), 4, np.ascontiguousarray(blocking).tobytes(), dtype="f4")
        for t in (tex, vox.area, vox.normal, vox.albedo, vox.albedo_back):
            if t is not None:
                t.filter = (moderngl.NEAREST, moderngl.NEAREST)
        vox.emission.release()
        # The gather runs over this list, not the whole fine grid: a workgroup straddling a wall would leave most
        # of its SIMD lanes idle for the whole VPL loop.
        z, y, x = np.nonzero(area[..., 3] > 0)
        cells = np.stack([x, y, z, np.zeros_like(x)], axis=1).astype(np.int32)
        surfaces = ctx.buffer(cells.tobytes() if len(cells) else np.zeros(4, np.int32).tobytes())
        normals = arrays["normal"][z, y, x, :3]
        out.append(GeometryVolume(tex, fine, vox.area, vox.normal, vox.albedo, surfaces=surfaces,
                                  surface_count=len(cells), cells=cells[:, :3], surface_normal=normals,
                                  surface_area=layer_area(area[z, y, x, 3], normals, fine.cell),
                                  surface_albedo=side_albedo(arrays, cells[:, :3]), albedo_back=vox.albedo_back,
                                  front=vox.front,
                                  **volume_fields(ctx, crossing_layers(area, arrays["normal"], grid))))
    return out


def side_albedo(arrays: dict, cells: np.ndarray) -> np.ndarray:
    """(2, R, 3): the front and back side's albedo at `cells` (R, 3) xyz from VoxelVolumes.read() arrays (the
    front's for both where the voxelisation kept one albedo)."""
    x, y, z = cells.T
    front = arrays["albedo"][z, y, x, :3]
    back = arrays["albedo_back"][z, y, x, :3] if "albedo_back" in arrays else front
    return np.stack([front, back])


def absorb(ctx, programs, state: LpvGridState, gv: GeometryVolume, add: bool) -> None:
    """Front/back irradiance of every surface voxel from the flux occlusion stopped (lpv/absorb.glsl); `add`
    adds it to the bounce totals instead of starting them."""
    import moderngl

    size = gv.fine.size
    for name in ("front", "back", "front_total", "back_total"):
        if getattr(state, name) is None:
            t = ctx.texture3d(size, 4, dtype="f4")
            t.filter = (moderngl.NEAREST, moderngl.NEAREST)
            setattr(state, name, t)
    prog = programs.compute("lpv/absorb.glsl", {"MODE_ADD": 1} if add else None)
    state.face_flux.bind_to_storage_buffer(6)
    bind_named(prog, [("u_geometry", gv.blocking), ("u_voxel_normal", gv.normal), ("u_voxel_area", gv.area)])
    set_uniform(prog, "u_grid_size", tuple(int(c) for c in state.grid.size))
    set_uniform(prog, "u_grid_cell", float(state.grid.cell))
    bind_images([state.front, state.back, state.front_total, state.back_total], read=True)
    dispatch(prog, size)


def inject_bounce(ctx, programs, state: LpvGridState, gv: GeometryVolume, bound: float) -> float:
    """Re-inject the light the surfaces absorbed in the last pass, times their albedo (lpv/bounce.glsl)."""
    scale = FIXED_RANGE / max(bound, 1e-12)
    state.accum_ints.clear()
    prog = programs.compute("lpv/bounce.glsl")
    bind_named(prog, [("u_front", state.front), ("u_back", state.back), ("u_voxel_normal", gv.normal),
                      ("u_voxel_area", gv.area), ("u_voxel_albedo", gv.albedo),
                      ("u_voxel_albedo_back", gv.albedo_back or gv.albedo)])
    set_uniform(prog, "u_fine_origin", tuple(float(c) for c in gv.fine.origin))
    set_uniform(prog, "u_fine_size", tuple(gv.fine.size))
    bind_grid(prog, state.grid)
    set_uniform(prog, "u_fixed_scale", float(scale))
    state.accum_ints.bind_to_storage_buffer(4)
    dispatch(prog, gv.fine.size)
    return resolve(ctx, programs, state, scale, state.ping)


