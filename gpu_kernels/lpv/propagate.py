# SPDX-License-Identifier: GPL-3.0-or-later
"""The classic LPV transport (LpvSettings.transport = "propagate"): the Kaplanyan–Dachsbacher face scheme with
fuzzy occlusion, bounce by bounce, until a step moves less than ε of the injected flux."""
from __future__ import annotations

import numpy as np

from ..common.grid import Grid
from ..gl.bind import bind_images, bind_named, dispatch, set_uniform, write_uniform
from .occlusion import absorb, inject_bounce
from .settings import LpvSettings
from .sh import SH_FLUX, transfer_matrices
from .state import FIXED_RANGE, LpvGridState, Volumes, copy_volumes, make_volumes


CHECK_EVERY = 4  # propagation steps between reads of the moved-flux counter (each read waits for the GPU)


def propagate(ctx, programs, state: LpvGridState, source: Volumes, injected_flux: float, gv_texture,
              settings: LpvSettings, accumulate: bool = True) -> dict:
    """Propagate `source` until a step moves < ε of the injected flux (checked every CHECK_EVERY steps);
    with `accumulate`, add every step to state.accum (needed by the intensity lookup only)."""
    prog = programs.compute("lpv/propagate.glsl", {"MODE_ACCUMULATE": 1} if accumulate else None)
    nx, ny, nz = state.grid.size
    flux_scale = FIXED_RANGE / max(injected_flux, 1e-12) / 4  # moved flux never exceeds the injected flux
    set_uniform(prog, "u_grid_size", (int(nx), int(ny), int(nz)))
    set_uniform(prog, "u_occlusion", bool(settings.occlusion and gv_texture is not None))
    set_uniform(prog, "u_clamp_negative", bool(settings.clamp_negative))
    set_uniform(prog, "u_flux_scale", float(flux_scale))
    transfer, incident = transfer_matrices()
    if "u_transfer" in prog:
        # GLSL mat4 is column-major: pass each matrix transposed.
        write_uniform(prog, "u_transfer", transfer.transpose(0, 2, 1))
        write_uniform(prog, "u_incident", incident)
    if gv_texture is not None:
        gv_texture.use(location=3)
    set_uniform(prog, "u_geometry", 3)
    src, dst = source, state.ping
    state.face_flux.clear()
    state.face_flux.bind_to_storage_buffer(6)
    moved_history = []
    for step in range(settings.max_iterations):
        bind_named(prog, list(zip(("u_src_r", "u_src_g", "u_src_b"), src.textures())))
        bind_images(dst.textures())
        bind_images(state.accum.textures(), 3, read=True)
        check = (step + 1) % CHECK_EVERY == 0 or step + 1 == settings.max_iterations
        if check:
            state.counter.write(np.zeros(1, np.int32).tobytes())
        state.counter.bind_to_storage_buffer(5)
        dispatch(prog, (nx, ny, nz))
        src, dst = dst, (state.pong if dst is state.ping else state.ping)
        if check:
            moved = int(np.frombuffer(state.counter.read(), np.int32)[0]) / flux_scale
            moved_history.append(moved)
            if moved < settings.epsilon * injected_flux:
                break
    state.last = src
    return {"iterations": step + 1, "moved": moved_history}


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


def step_fluxes(ctx, programs, grid: Grid, initial: np.ndarray, steps: int, settings: LpvSettings,
                blocking=None) -> list:
    """Diagnostics: propagate SH volumes `initial` ((nz, ny, nx, 3, 4): RGB × 4 coefficients) for `steps` steps
    with the real shaders and return the signed flux (RGB) each step leaves in the grid: Σ c0·2√π per channel."""
    state = LpvGridState(ctx, grid)
    try:
        source = make_volumes(ctx, grid, initial)
        fluxes = []
        src = source
        one = LpvSettings(**{**settings.__dict__, "max_iterations": 1, "epsilon": 0.0})
        for _ in range(steps):
            propagate(ctx, programs, state, src, 1.0, blocking, one)
            out = state.last
            data = np.stack([np.frombuffer(t.read(), np.float32).reshape(grid.shape_zyx + (4,))
                             for t in out.textures()], axis=-2)
            fluxes.append(data[..., 0].astype(np.float64).sum(axis=(0, 1, 2)) * SH_FLUX)
            src = make_volumes(ctx, grid, data)  # copy out of ping before the next step overwrites it
        return fluxes
    finally:
        state.release()
