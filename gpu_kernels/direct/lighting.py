# SPDX-License-Identifier: GPL-3.0-or-later
"""Diffuse Direct and Glossy Direct: every G-buffer pixel lit by every light, shadowed (direct/light.glsl)."""
from __future__ import annotations

from ..gl.bind import bind_lights, bind_samplers, dispatch, set_uniform, set_uniforms
from .gbuffer import GBuffer
from .shadows import ShadowAtlas


def render_direct_light(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas, material_lut=None) -> dict:
    """{"diffuse": Diffuse Direct (irradiance/π), "glossy": Glossy Direct} for every G-buffer pixel, as RGBA32F
    textures. `material_lut`: the materials' Principled table (direct/geometry.MaterialTextures.lut); None for
    G-buffers with no camera (the surface atlas), whose Glossy Direct is 0."""
    w, h = gbuffer.size
    out = {name: ctx.texture((w, h), 4, dtype="f4") for name in ("diffuse", "glossy")}
    prog = programs.compute("direct/light.glsl")
    out["diffuse"].bind_to_image(0, read=False, write=True)
    out["glossy"].bind_to_image(1, read=False, write=True)
    unit = 0
    for name in ("position", "normal", "geo_normal", "glossy", "specular"):
        unit = bind_samplers(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    if material_lut is not None:
        unit = bind_samplers(prog, "u_material_lut", [material_lut], unit)
    bind_lights(prog, shadows, unit)
    set_uniforms(prog, {"u_size": (w, h), "u_glossy_enabled": material_lut is not None, "u_eye": tuple(gbuffer.eye),
                        "u_forward": tuple(gbuffer.forward), "u_ortho": bool(gbuffer.ortho)})
    dispatch(prog, (w, h), local=8)
    return out
