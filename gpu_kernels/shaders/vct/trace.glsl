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
// MODE_FIXUP: full resolution, in place: only pixels vct/upsample.glsl marked (a < 0: no low-resolution sample lies
// on their surface) are traced; the rest keep their upsampled value.
#include "vct/common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_position;      // xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform sampler2D u_geo_normal;    // xyz geometric normal (faces the viewer)
uniform ivec2 u_image_size;        // output size
uniform ivec2 u_full_size;         // G-buffer size
uniform int u_scale;               // G-buffer pixels per output texel (1, 2, 4)
uniform vec2 u_rotation;           // (cos φ, sin φ) of the cone set's turn about the normal (temporal jitter)
#if defined(MODE_FIXUP)
layout(rgba32f, binding = 0) uniform image2D u_indirect;
#else
layout(rgba32f, binding = 0) uniform writeonly image2D u_indirect;
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
#if defined(MODE_FIXUP)
    if (imageLoad(u_indirect, px).a >= 0.0) return;
    ivec2 src = px;
#else
    ivec2 src = min(px * u_scale + u_scale / 2, u_full_size - 1);
#endif
    vec4 pos = texelFetch(u_position, src, 0);
    if (pos.w < 0.5) {
        imageStore(u_indirect, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, src, 0).xyz);
    vec3 geo_n = normalize(texelFetch(u_geo_normal, src, 0).xyz);
    vec4 e = gather_irradiance(pos.xyz, n, geo_n, u_rotation);
    imageStore(u_indirect, px, vec4(e.rgb / VCT_PI, e.a));
}
