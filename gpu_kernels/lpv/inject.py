# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV injection: RSM texels as VPLs, summed in fixed point into each cascade's SH volumes (Kaplanyan and
Dachsbacher 2010: light injection). World light is a light like the others (common/lights.py: the sky light): its
shadow views have RSMs too, so the surfaces the sky reaches inject its first bounce here."""
from __future__ import annotations

from ..gl.bind import bind_grid, dispatch, set_uniform
from .gather import rsm_uniforms, vpl_list
from .rsm import Rsm, flux_bound
from .state import FIXED_RANGE, LpvGridState, resolve


def inject(ctx, programs, rsm: Rsm, shadows, materials, state: LpvGridState, downsample: int = 1) -> float:
    """RSM texels → fixed-point SH sums → state.injected. Returns the injected flux (W, sum of RGB)."""
    scale = FIXED_RANGE / max(flux_bound(shadows.buffers), 1e-30)
    state.accum_ints.clear()
    prog = programs.compute("lpv/inject.glsl", shadows.defines)
    blocks = rsm_uniforms(prog, rsm, shadows, materials, downsample)
    set_uniform(prog, "u_fixed_scale", float(scale))
    bind_grid(prog, state.grid)
    state.accum_ints.bind_to_storage_buffer(4)
    dispatch(prog, (blocks[0], blocks[1]), local=8)
    return resolve(ctx, programs, state, scale, state.injected)


def inject_all(ctx, programs, rsm: Rsm, shadows, materials, grids: list, downsample: int = 1,
               gather_vpls: int = 0) -> list:
    """Inject the RSM VPLs into a fresh state per cascade (finest first). With `gather_vpls` > 0 they are listed
    for the gathered first bounce (state.vpls) instead of injected."""
    states = []
    for grid in grids:
        state = LpvGridState(ctx, grid)
        if gather_vpls:
            state.vpls = vpl_list(ctx, programs, rsm, shadows, materials, grid, gather_vpls)
        else:
            state.injected_flux = inject(ctx, programs, rsm, shadows, materials, state, downsample)
        states.append(state)
    return states
