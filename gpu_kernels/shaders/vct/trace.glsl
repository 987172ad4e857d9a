// SPDX-License-Identifier: GPL-3.0-or-later
// VCT final gather per G-buffer pixel (Freed 2018, §4.5.2, Algorithm 3): diffuse cones over the hemisphere of the
// shading normal, started from the geometric tangent plane (vct/common.glsl). Output: rgb = Diffuse Indirect
// (irradiance / π, albedo divided out as in Cycles' pass, docs/conventions.md), a = voxel ambient occlusion
// (cosine-weighted transmittance; 1 = unoccluded).
//
// Reduced resolution (inferred lighting, Kircher and Lawrance 2009): with u_scale = s the output is ceil(W/s) ×
// ceil(H/s) and output texel i gathers at full-resolution pixel i·s + s/2 (clamped to the image), so every traced
// sample lies exactly on a G-buffer pixel and vct/upsample.glsl can compare its position and normal with its
// neighbours'.
// MODE_MARKED: in place, only the marked texels are traced, listed by the pass that marked them (storage buffer 5,
// u_marked of them, u_list_width a row of the dispatch): at full resolution (u_scale 1) the pixels
// vct/upsample.glsl marked (no low-resolution sample lies on their surface); at the reduced one the texels
// vct/reuse.glsl found no gather of the last view for. One marked texel per invocation: swept over the image, a
// SIMD group holding one marked texel among idle lanes cost as much as eight.
// MODE_RECORD: the trace, keeping every texel's sub-ray hits (vct/hits.glsl); MODE_REPLAY: the same image from
// those hits and the current volumes, a texel the record could not keep traced again.
#include "vct/common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_position;      // xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform sampler2D u_geo_normal;    // xyz geometric normal (faces the viewer)
uniform ivec2 u_image_size;        // output size
uniform ivec2 u_full_size;         // G-buffer size
uniform int u_scale;               // G-buffer pixels per output texel (1, 2, 4)
uniform vec2 u_rotation;           // (cos φ, sin φ) of the cone set's turn about the normal (temporal jitter)
layout(rgba32f, binding = 0) uniform writeonly image2D u_indirect;
#if defined(MODE_MARKED)
layout(std430, binding = 5) readonly buffer MarkedList { ivec2 marked_texels[]; };
uniform int u_marked;
uniform int u_list_width;
#endif

#if defined(MODE_REPLAY)
// The texel's Diffuse Indirect as trace_cone_crossing and gather_irradiance sum it, term by term in their order.
vec3 replay(uvec4 header) {
    const float inv_ns = 1.0 / float(SUBRAYS);
    vec3 e = vec3(0.0), radiance = vec3(0.0);
    int cone = 0;
    uint chunk = header.x;
    for (uint h = 0u; h < header.y; ++h) {
        uint i = hit_at(h, chunk);
        vec4 point = hit_points[i];
        uint tag = hit_tags[i];
        end_cones(e, radiance, cone, int(tag & 31u));
        vec4 s = volume_at((tag >> 5) & 7u, point.xyz, float(tag >> 8));
        float alpha = point.w;
        radiance += inv_ns * alpha * s.rgb / s.a;
    }
    end_cones(e, radiance, cone, u_cone_count);
    return e;
}
#endif

void main() {
#if defined(MODE_MARKED)
    int listed = int(gl_GlobalInvocationID.y) * u_list_width + int(gl_GlobalInvocationID.x);
    if (int(gl_GlobalInvocationID.x) >= u_list_width || listed >= u_marked) return;
    ivec2 px = marked_texels[listed];
#else
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
#endif
    uint texel = uint(px.y * u_image_size.x + px.x);
#if defined(MODE_REPLAY)
    uvec4 header = hit_headers[texel];
    if (header.w == HIT_BACKGROUND) {
        imageStore(u_indirect, px, vec4(0.0));
        return;
    }
    if (header.w == HIT_RECORDED) {
        imageStore(u_indirect, px, vec4(replay(header) / VCT_PI, uintBitsToFloat(header.z)));
        return;
    }
#endif
    ivec2 src = min(px * u_scale + u_scale / 2, u_full_size - 1);
    vec4 pos = texelFetch(u_position, src, 0);
    if (pos.w < 0.5) {
#if defined(MODE_RECORD)
        hit_headers[texel] = uvec4(0u, 0u, 0u, HIT_BACKGROUND);
#endif
        imageStore(u_indirect, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, src, 0).xyz);
    vec3 geo_n = normalize(texelFetch(u_geo_normal, src, 0).xyz);
    vec4 e = gather_irradiance(pos.xyz, n, geo_n, u_rotation);
    vec4 value = vec4(e.rgb / VCT_PI, e.a);
#if defined(MODE_RECORD)
    hit_headers[texel] = uvec4(g_first, g_hits, floatBitsToUint(value.a), g_overflow ? 0u : HIT_RECORDED);
#endif
    imageStore(u_indirect, px, value);
}
