// SPDX-License-Identifier: GPL-3.0-or-later
// VCT specular cone (Freed 2018, §4.5.2: "five [cones] for diffuse light and one for a specular highlight", oriented
// along reflect(−v, n)): one glossy cone per G-buffer pixel → Glossy Indirect, the radiance arriving from around the
// mirror direction, i.e. the reflected light divided by Glossy Color as in Cycles' pass (docs/conventions.md).
//
// Aperture from Principled roughness r (vct/specular.py documents it): Blender's GGX uses α = r². Sampling the GGX
// normal distribution gives tan²θ_h = α²·ξ / (1 − ξ), so half of the microfacet normals lie within θ_h = atan(α) of
// n; a normal tilted by θ_h turns the reflected ray by 2·θ_h. The cone's half-angle is therefore 2·atan(α): it holds
// the reflected directions of the median half of the lobe (r = 0.5 → 28°, r = 0.2 → 4.6°, r = 0 → a ray). Freed 2018
// used 0.1·π·r "determined experimentally" (9° at r = 0.5), narrower for rough and wider for near-mirror surfaces.
// The half-angle is capped at 45° (r ≈ 0.8); above u_roughness_cutoff the cone is skipped (Glossy Indirect = 0).
#include "vct/common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_position;      // xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform sampler2D u_geo_normal;    // xyz geometric normal (faces the viewer)
uniform sampler2D u_glossy;        // rgb Glossy Color, w roughness (direct/gbuffer.glsl)
uniform ivec2 u_image_size;
uniform vec3 u_camera_position;
uniform vec3 u_camera_forward;
uniform bool u_camera_ortho;
uniform float u_roughness_cutoff;
layout(rgba32f, binding = 0) uniform writeonly image2D u_out;   // rgb Glossy Indirect, a = 1 where a cone ran
layout(std430, binding = 3) buffer Counter { uint traced; };

const float MAX_HALF_ANGLE = 0.785398163;   // 45°

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
    vec4 pos = texelFetch(u_position, px, 0);
    vec4 glossy = texelFetch(u_glossy, px, 0);
    // Skipped where nothing is glossy (Diffuse BSDF), or too rough for one cone: those pixels cost one fetch.
    if (pos.w < 0.5 || max(glossy.r, max(glossy.g, glossy.b)) <= 0.0 || glossy.w > u_roughness_cutoff) {
        imageStore(u_out, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    vec3 geo_n = normalize(texelFetch(u_geo_normal, px, 0).xyz);
    vec3 v = u_camera_ortho ? -u_camera_forward : normalize(u_camera_position - pos.xyz);
    vec3 r = reflect(-v, n);
    // A smooth-shading normal can reflect below the geometric tangent plane; lift the axis just above it (the
    // cone would otherwise start by marching into its own surface).
    float below = dot(r, geo_n);
    if (below < 0.01) r = normalize(r + (0.01 - below) * geo_n);
    float alpha = glossy.w * glossy.w;
    float tan_half = tan(min(2.0 * atan(alpha), MAX_HALF_ANGLE));
    ConeResult c = trace_cone(pos.xyz, cone_origin(pos.xyz, geo_n), geo_n, r, tan_half);
    vec3 radiance = c.radiance;  // the world it reflects is Glossy Direct (direct/ggx.glsl: sky_glossy)
    atomicAdd(traced, 1u);
    imageStore(u_out, px, vec4(radiance, 1.0));
}
