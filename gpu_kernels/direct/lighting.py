# SPDX-License-Identifier: GPL-3.0-or-later
"""Diffuse Direct: every G-buffer pixel lit by every light, shadowed (direct/light.glsl)."""
from __future__ import annotations

from ..gl.bind import bind_lights, bind_samplers, dispatch, set_uniform
from .gbuffer import GBuffer
from .shadows import ShadowAtlas


def render_direct_light(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas):
    """Diffuse Direct (irradiance/π) for every G-buffer pixel, as an RGBA32F texture."""
    w, h = gbuffer.size
    out = ctx.texture((w, h), 4, dtype="f4")
    prog = programs.compute("direct/light.glsl")
    out.bind_to_image(0, read=False, write=True)
    unit = 0
    for name in ("position", "normal", "geo_normal"):
        unit = bind_samplers(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    bind_lights(prog, shadows, unit)
    set_uniform(prog, "u_size", (w, h))
    dispatch(prog, (w, h), local=8)
    return out
