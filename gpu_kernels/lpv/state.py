# SPDX-License-Identifier: GPL-3.0-or-later
"""The GPU state of one LPV cascade: the cascades' grids, SH volumes, the fixed-point injection accumulator and
its resolve into float volumes."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from ..gl.bind import dispatch, set_uniform, zero_texture
from ..scene import Scene
from .settings import LpvSettings
from .sh import SH_FLUX

FIXED_RANGE = 2.0 ** 29  # fixed-point headroom: a cell's coefficient sum stays below 2³¹ (see rsm.flux_bound)


def cascade_grids(scene: Scene, settings: LpvSettings) -> list[Grid]:
    """The coarsest cascade covers the scene; each finer one has half the cell size, centred on the camera
    (clamped into the scene) and snapped to whole cells of the coarse grid's lattice so small camera moves don't shift
    it and every cascade's cells nest in the next one's."""
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
        grids.append(Grid.centered(centre, cell, (n, n, n), anchor=coarse.origin))
    return grids[::-1]  # finest first


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


def make_volumes(ctx, grid: Grid, data: np.ndarray | None = None) -> Volumes:
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
            zero_texture(ctx, t)
    return Volumes(*texs)


class LpvGridState:
    """GPU state of one cascade: injection accumulator, ping-pong volumes and the accumulation volume."""

    def __init__(self, ctx, grid: Grid):
        self.grid = grid
        n = int(np.prod(grid.size))
        self.accum_ints = ctx.buffer(reserve=n * 12 * 4)
        self.injected = make_volumes(ctx, grid)
        self.accum = make_volumes(ctx, grid)
        self.ping = make_volumes(ctx, grid)
        self.pong = make_volumes(ctx, grid)
        self.injected_next = make_volumes(ctx, grid)  # a bounce's source (ping/pong are the propagation buffers)
        self.counter = ctx.buffer(reserve=4)
        self.face_flux = ctx.buffer(reserve=n * 6 * 16)  # vec4 per cell and direction of travel
        self.front = self.back = None  # absorbed-light irradiance per fine voxel, last pass (set by `absorb`)
        self.front_total = self.back_total = None  # summed over bounces
        self.vpls = None  # the RSM's VPLs for the gathered transport (lpv/gather.vpl_list)

    def release(self):
        for obj in (self.accum_ints, self.injected, self.accum, self.ping, self.pong, self.injected_next,
                    self.counter, self.face_flux,
                    self.front, self.back, self.front_total, self.back_total, self.vpls):
            if obj is not None:
                obj.release()


def resolve(ctx, programs, state: LpvGridState, scale: float, target: Volumes, add: bool = False) -> float:
    """Fixed-point sums → float volumes; returns the flux they hold (sum over RGB of |band 0|·2√π)."""
    prog = programs.compute("lpv/resolve.glsl", {"MODE_ADD": 1} if add else None)
    state.accum_ints.bind_to_storage_buffer(4)
    for unit, tex in enumerate(target.textures()):
        tex.bind_to_image(unit, read=True, write=True)
    set_uniform(prog, "u_grid_size", tuple(int(c) for c in state.grid.size))
    set_uniform(prog, "u_fixed_scale", float(scale))
    nx, ny, nz = state.grid.size
    dispatch(prog, (nx, ny, nz))
    ints = np.frombuffer(state.accum_ints.read(), np.int32).reshape(-1, 3, 4)
    return float(np.abs(ints[:, :, 0].astype(np.float64)).sum() / scale * SH_FLUX)


def copy_volumes(ctx, src: Volumes, dst: Volumes) -> None:
    for a, b in zip(src.textures(), dst.textures()):
        b.write(a.read())
