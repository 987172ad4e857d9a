// SPDX-License-Identifier: GPL-3.0-or-later
// vct_inject by parts (vct/parts.py): one face volume of the radiance L_g = albedo_g ⊙ Σ_p k_p ⊙ E_g,p/π, where part p
// was injected per unit of its own colour and k_p scales it back (per channel, relative to the transport's unit,
// vct/colours.py), summed in the parts' order, and albedo_g is the face's (vct/face_albedo.glsl). The coverage α_g
// is the geometry's, the same in every part. Run once per face direction; the sum starts zeroed
// (gl/bind.texture3d), so voxels without surfaces are left alone. The parts' samplers are read by name, not from an
// array indexed in a loop (vct/arrays.glsl: Mesa 22 got such reads wrong).
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_part0, u_part1, u_part2;                     // this face of each part (vct/parts.PARTS)
uniform sampler3D u_albedo;                                      // this face's albedo
layout(rgba32f, binding = 0) uniform writeonly image3D u_face;   // this face of the sum
uniform ivec3 u_grid_size;
uniform int u_parts;
uniform vec3 u_weight0, u_weight1, u_weight2;                    // k_p

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 first = texelFetch(u_part0, v, 0);
    if (first.a <= 0.0) return;   // no coverage: no part has light there
    vec3 sum = u_weight0 * first.rgb;
    if (u_parts > 1) sum += u_weight1 * texelFetch(u_part1, v, 0).rgb;
    if (u_parts > 2) sum += u_weight2 * texelFetch(u_part2, v, 0).rgb;
    imageStore(u_face, v, vec4(texelFetch(u_albedo, v, 0).rgb * sum, first.a));
}
