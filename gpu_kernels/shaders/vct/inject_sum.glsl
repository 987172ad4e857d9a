// SPDX-License-Identifier: GPL-3.0-or-later
// vct_inject by parts (vct/parts.py): one face volume of the sum L_g = Σ_p k_p ⊙ L_g,p, where part p was injected per
// unit of its own colour and k_p scales it back (per channel, relative to the transport's unit, vct/colours.py),
// summed in the parts' order. The coverage α_g is the geometry's, the same in every part. Run once per face
// direction; the sum starts zeroed (vct.texture3d), so voxels without surfaces are left alone.
#define MAX_PARTS 3   // vct/parts.PARTS
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_part[MAX_PARTS];                   // this face of each part
layout(rgba32f, binding = 0) uniform writeonly image3D u_face;   // this face of the sum
uniform ivec3 u_grid_size;
uniform int u_parts;
uniform vec3 u_weight[MAX_PARTS];                      // k_p

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 first = texelFetch(u_part[0], v, 0);
    if (first.a <= 0.0) return;   // no coverage: no part has light there
    vec3 sum = u_weight[0] * first.rgb;
    for (int p = 1; p < u_parts; ++p) sum += u_weight[p] * texelFetch(u_part[p], v, 0).rgb;
    imageStore(u_face, v, vec4(sum, first.a));
}
