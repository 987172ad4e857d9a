// SPDX-License-Identifier: GPL-3.0-or-later
// Material inputs of one draw call (see direct/geometry.py: bind_material) and the diffuse albedo they give.
#pragma once
#include "common/principled.glsl"

uniform vec3 u_base_color;
uniform float u_metallic;
uniform float u_roughness;
uniform bool u_specular_layer;   // Principled BSDF: a dielectric GGX layer sits on the diffuse base
uniform vec3 u_emission;
uniform bool u_use_texture;
uniform sampler2D u_base_texture;

// Cycles' Diffuse Color: base colour (or texture) × (1 − metallic) × the Principled diffuse share at μ = n·v.
vec3 diffuse_albedo(vec2 uv, float mu) {
    vec3 color = u_use_texture ? texture(u_base_texture, uv).rgb : u_base_color;
    float share = (1.0 - u_metallic) * (u_specular_layer ? principled_diffuse_share(mu, u_roughness) : 1.0);
    return color * share;
}

// Cycles' Glossy Color: the directional albedo of the glossy closures (bsdf_albedo, which for microfacet closures
// includes the estimated Fresnel albedo). The dielectric GGX layer's albedo is exactly what the layering takes
// from the diffuse base, 1 − diffuse share (same table, μ = n·v; ≈ 0.04 at normal incidence, IOR 1.5), weighted by
// 1 − metallic; the metallic part is approximated by metallic × base colour (the F82-tint conductor's albedo at
// normal incidence; it rises towards 1 at grazing angles, which this ignores). Diffuse BSDF: no glossy closure.
vec3 glossy_albedo(vec2 uv, float mu) {
    if (!u_specular_layer) return vec3(0.0);
    vec3 color = u_use_texture ? texture(u_base_texture, uv).rgb : u_base_color;
    float dielectric = 1.0 - principled_diffuse_share(mu, u_roughness);
    return (1.0 - u_metallic) * vec3(dielectric) + u_metallic * color;
}
