// SPDX-License-Identifier: GPL-3.0-or-later
// Direct diffuse light per pixel from the G-buffer: sun, point, spot (Cycles' smoothstep cone), and polygon lights
// (area lights and emissive triangles) integrated exactly with Lambert's polygon formula, all shadowed through the
// shadow atlas. Output is Cycles' Diffuse Direct pass: irradiance/π, albedo divided out (docs/conventions.md).
#include "common/lights.glsl"
#include "common/light_eval.glsl"
#include "direct/eval.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_diffuse_direct;
uniform sampler2D u_position;      // xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform sampler2D u_geo_normal;    // xyz geometric normal (faces the viewer)
uniform int u_light_count;
uniform ivec2 u_size;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_size))) return;
    vec4 pos = texelFetch(u_position, px, 0);
    if (pos.w < 0.5) {
        imageStore(u_diffuse_direct, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    vec3 geo_n = normalize(texelFetch(u_geo_normal, px, 0).xyz);
    vec3 irradiance = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        irradiance += light_irradiance(lights[i], pos.xyz, n, geo_n);
    }
    imageStore(u_diffuse_direct, px, vec4(irradiance / PI, 1.0));
}
