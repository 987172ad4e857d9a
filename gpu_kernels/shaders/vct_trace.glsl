// VCT final gather per G-buffer pixel (seed 004 §4.5.2, Algorithm 3): diffuse cones over the hemisphere of the
// shading normal, started from the geometric tangent plane (vct_common.glsl). Output: rgb = Diffuse Indirect
// (irradiance / π, albedo divided out as in Cycles' pass, design.md §3), a = voxel ambient occlusion
// (cosine-weighted transmittance; 1 = unoccluded).
#include "vct_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_position;      // xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform sampler2D u_geo_normal;    // xyz geometric normal (faces the viewer)
uniform ivec2 u_image_size;
layout(rgba32f, binding = 0) uniform writeonly image2D u_indirect;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
    vec4 pos = texelFetch(u_position, px, 0);
    if (pos.w < 0.5) {
        imageStore(u_indirect, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    vec3 geo_n = normalize(texelFetch(u_geo_normal, px, 0).xyz);
    vec4 e = gather_irradiance(pos.xyz, n, geo_n);
    imageStore(u_indirect, px, vec4(e.rgb / VCT_PI, e.a));
}
