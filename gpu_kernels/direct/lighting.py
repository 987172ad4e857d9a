# SPDX-License-Identifier: GPL-3.0-or-later
"""Diffuse Direct and Glossy Direct: every G-buffer pixel lit by every light, shadowed (direct/light.glsl)."""
from __future__ import annotations

from ..common import lights as lb
from ..gl.bind import bind_lights, bind_samplers, dispatch, set_uniform, set_uniforms
from .gbuffer import GBuffer
from .shadows import ShadowAtlas


def render_direct_light(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas, material_lut=None, sky=None) -> dict:
    """{"diffuse": Diffuse Direct (irradiance/π), "glossy": Glossy Direct} for every G-buffer pixel, as RGBA32F
    textures. `material_lut`: the materials' Principled table (direct/geometry.MaterialTextures.lut); None for
    G-buffers with no camera (the surface atlas), whose Glossy Direct is 0. `sky`: the sky light's shares from
    render_sky_visibility (None: computed here)."""
    w, h = gbuffer.size
    out = {name: ctx.texture((w, h), 4, dtype="f4") for name in ("diffuse", "glossy")}
    prog = programs.compute("direct/light.glsl")
    out["diffuse"].bind_to_image(0, read=False, write=True)
    out["glossy"].bind_to_image(1, read=False, write=True)
    unit = _bind_inputs(prog, gbuffer, shadows, material_lut)
    if sky is not None:
        bind_samplers(prog, "u_sky_shares", [sky], unit)
    set_uniform(prog, "u_sky_cached", sky is not None)
    dispatch(prog, (w, h), local=8)
    return out


def render_sky_visibility(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas, material_lut=None):
    """RGBA32F per G-buffer pixel: the sky light's visible shares (direct/light.glsl MODE_SKY: x of its cosine
    weight, y of the glossy lobe's, z its penumbra's half-width in metres), averaged over that penumbra on the
    pixel's own surface (direct/sky_filter.glsl), or None where the scene has no sky light. They depend on the
    G-buffer and the sky's shadow maps, not on the world's colour: the pipeline keeps them across world and light
    edits, and the Diffuse Direct pass reads them instead of testing the sky's hundreds of directions again."""
    if not any(int(t) == lb.LIGHT_SKY for t in shadows.buffers.lights["color_type"][:, 3]):
        return None
    w, h = gbuffer.size
    out = ctx.texture((w, h), 4, dtype="f4")
    prog = programs.compute("direct/light.glsl", {"MODE_SKY": None})
    out.bind_to_image(2, read=False, write=True)
    _bind_inputs(prog, gbuffer, shadows, material_lut)
    dispatch(prog, (w, h), local=8)
    return filter_sky_shares(ctx, programs, gbuffer, out)


def filter_sky_shares(ctx, programs, gbuffer: GBuffer, shares):
    """The sky's shares averaged over each pixel's penumbra on its own surface, one image axis at a time
    (direct/sky_filter.glsl); releases `shares`."""
    w, h = gbuffer.size
    prog = programs.compute("direct/sky_filter.glsl")
    unit = bind_samplers(prog, "u_position", [gbuffer.textures["position"]], 0)
    unit = bind_samplers(prog, "u_geo_normal", [gbuffer.textures["geo_normal"]], unit)
    set_uniform(prog, "u_size", (w, h))
    for axis in ((1, 0), (0, 1)):
        out = ctx.texture((w, h), 4, dtype="f4")
        bind_samplers(prog, "u_shares", [shares], unit)
        out.bind_to_image(0, read=False, write=True)
        set_uniform(prog, "u_axis", axis)
        dispatch(prog, (w, h), local=8)
        shares.release()
        shares = out
    return shares


def _bind_inputs(prog, gbuffer: GBuffer, shadows: ShadowAtlas, material_lut) -> int:
    """The G-buffer, the material table and the lights for direct/light.glsl; returns the next free texture unit."""
    unit = 0
    for name in ("position", "normal", "geo_normal", "glossy", "specular"):
        unit = bind_samplers(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    if material_lut is not None:
        unit = bind_samplers(prog, "u_material_lut", [material_lut], unit)
    unit = bind_lights(prog, shadows, unit)
    w, h = gbuffer.size
    set_uniforms(prog, {"u_size": (w, h), "u_glossy_enabled": material_lut is not None, "u_eye": tuple(gbuffer.eye),
                        "u_forward": tuple(gbuffer.forward), "u_ortho": bool(gbuffer.ortho)})
    return unit
