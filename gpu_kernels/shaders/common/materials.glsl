// SPDX-License-Identifier: GPL-3.0-or-later
// Material inputs of one draw call (see direct/geometry.py: bind_material) and the albedos they give.
#pragma once
#include "common/principled.glsl"

uniform vec3 u_base_color;
uniform float u_roughness;
uniform int u_material;            // the material's rows in u_material_lut
uniform sampler2D u_material_lut;  // common/principled.py: material_lut
uniform vec3 u_emission;
uniform bool u_use_texture;
uniform sampler2D u_base_texture;

vec3 base_color(vec2 uv) {
    return u_use_texture ? texture(u_base_texture, uv).rgb : u_base_color;
}

// Cycles' Diffuse Color: base colour (or texture) × what the layers above leave the diffuse base at μ = n·v.
vec3 diffuse_albedo(vec2 uv, float mu) {
    return base_color(uv) * principled_diffuse(u_material_lut, u_material, mu);
}

// Cycles' Glossy Color: the directional albedo estimates of the glossy closures (bsdf_albedo). Diffuse BSDF: 0.
vec3 glossy_albedo(vec2 uv, float mu) {
    return principled_glossy(u_material_lut, u_material, mu, base_color(uv));
}

// What Glossy Direct needs of the surface (direct/light.glsl): rgb the base colour, a the material's index.
vec4 glossy_inputs(vec2 uv) {
    return vec4(base_color(uv), float(u_material));
}
