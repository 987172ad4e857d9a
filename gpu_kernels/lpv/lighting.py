# SPDX-License-Identifier: GPL-3.0-or-later
"""The lpv_lighting pass: Diffuse Indirect per G-buffer pixel from the cascades — the cached transport's receivers'
irradiance (receivers.ReceiverLight), the surface voxels' absorbed irradiance (the flux lookup) or the SH intensity
convolved with the cosine (Kaplanyan's lookup)."""
from __future__ import annotations

from ..gl.bind import bind_named, bind_samplers, dispatch, set_uniform
from .receivers import ReceiverLight
from .settings import LpvSettings


def lighting(ctx, programs, gbuffer, states, gvs: list, settings: LpvSettings):
    """Diffuse Indirect (irradiance/π) per G-buffer pixel (RGBA32F texture) from `states`: a ReceiverLight, or the
    cascades' LpvGridStates (their flux totals or accumulated SH volumes)."""
    w, h = gbuffer.size
    out = ctx.texture((w, h), 4, dtype="f4")
    receiving = isinstance(states, ReceiverLight)
    flux_mode = not receiving and settings.lookup == "flux" and all(g is not None for g in gvs)
    dense = receiving and gvs[0].light_volumes is not None
    mode = {"MODE_RECEIVER_VOLUMES": 1} if dense else {"MODE_RECEIVERS": 1} if receiving else \
        {"MODE_FLUX": 1} if flux_mode else None
    if dense:
        states.write_volumes()  # first: it binds image units of its own
    prog = programs.compute("lpv/lighting.glsl", mode)
    out.bind_to_image(0, read=False, write=True)
    unit = bind_named(prog, [("u_position", gbuffer.textures["position"]), ("u_normal", gbuffer.textures["normal"])])
    grids = states.grids if receiving else [s.grid for s in states]
    n = len(grids)
    if receiving:
        if dense:
            per_cascade = {"u_receiver_light": gvs[0].light_volumes.volumes}
        else:
            per_cascade = {"u_index": [g.receiver_index for g in gvs]}
            states.records.bind_to_storage_buffer(6)
    elif flux_mode:
        per_cascade = {"u_front": [s.front_total for s in states], "u_back": [s.back_total for s in states],
                       "u_voxel_normal": [g.normal for g in gvs]}
    else:
        per_cascade = {f"u_accum_{c}": [s.accum.textures()[i] for s in states] for i, c in enumerate("rgb")}
    if receiving or flux_mode:
        fine_origin = [tuple(float(c) for c in g.fine.origin) for g in gvs]
        set_uniform(prog, "u_fine_origin", fine_origin + [fine_origin[-1]] * (4 - n))
        set_uniform(prog, "u_fine_size", [tuple(g.fine.size) for g in gvs] + [(1, 1, 1)] * (4 - n))
    for name, texs in per_cascade.items():
        unit = bind_samplers(prog, name, texs, unit, pad_to=max(4, len(texs)))
    origins = [tuple(float(c) for c in g.origin) for g in grids]
    set_uniform(prog, "u_grid_origin", origins + [origins[-1]] * (4 - n))
    set_uniform(prog, "u_grid_cell", [float(g.cell) for g in grids] + [1.0] * (4 - n))
    set_uniform(prog, "u_grid_size", [tuple(int(c) for c in g.size) for g in grids] + [(1, 1, 1)] * (4 - n))
    set_uniform(prog, "u_cascades", n)
    set_uniform(prog, "u_blend_cells", float(settings.blend_cells))
    set_uniform(prog, "u_damping", bool(settings.damping))
    set_uniform(prog, "u_image_size", (w, h))
    dispatch(prog, (w, h), local=8)
    return out
