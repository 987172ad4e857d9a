# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV injection: RSM texels as VPLs and world light at the grid's open border, summed in fixed point into each
cascade's SH volumes (Kaplanyan and Dachsbacher 2010: light injection)."""
from __future__ import annotations

import math

from ..common.grid import Grid
from ..gl.bind import bind_grid, dispatch, set_uniform
from .gather import rsm_uniforms, vpl_list
from .rsm import Rsm
from .state import FIXED_RANGE, LpvGridState, resolve


def sky_flux_bound(grid: Grid, world_color) -> float:
    """Flux the world can push through the grid's border faces: π·L_max·(border area)."""
    nx, ny, nz = grid.size
    border = 2 * (nx * ny + ny * nz + nx * nz) * grid.cell ** 2
    return math.pi * float(max(world_color[:3])) * border


def inject(ctx, programs, rsm: Rsm | None, shadows, state: LpvGridState, world_color=(0.0, 0.0, 0.0),
           gv=None, downsample: int = 1, vpls: bool = True) -> float:
    """RSM texels (unless not `vpls`: then `rsm` may be None) and world light at the open border → fixed-point SH
    sums → state.injected. Returns the injected flux (W, sum of RGB)."""
    grid = state.grid
    sky = max(world_color[:3]) > 0
    bound = (rsm.flux_bound if vpls else 0.0) + (sky_flux_bound(grid, world_color) if sky else 0.0)
    scale = FIXED_RANGE / max(bound, 1e-30)
    state.accum_ints.clear()
    if vpls:
        prog = programs.compute("lpv/inject.glsl")
        blocks = rsm_uniforms(prog, rsm, shadows, downsample)
        set_uniform(prog, "u_fixed_scale", float(scale))
        bind_grid(prog, grid)
        state.accum_ints.bind_to_storage_buffer(4)
        dispatch(prog, (blocks[0], blocks[1]), local=8)
    if sky:
        sky_prog = programs.compute("lpv/sky.glsl")
        bind_grid(sky_prog, grid)
        set_uniform(sky_prog, "u_world", tuple(float(c) for c in world_color[:3]))
        set_uniform(sky_prog, "u_fixed_scale", float(scale))
        set_uniform(sky_prog, "u_occlusion", gv is not None)
        if gv is not None:
            gv.blocking.use(location=0)
        set_uniform(sky_prog, "u_geometry", 0)
        state.accum_ints.bind_to_storage_buffer(4)
        nx, ny, nz = grid.size
        dispatch(sky_prog, (nx, ny, nz))
    return resolve(ctx, programs, state, scale, state.injected)


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
