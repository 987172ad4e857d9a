// SPDX-License-Identifier: GPL-3.0-or-later
// The extrapolated bounce tail of vct/bounce.py on one voxel face volume (common/bounce_tail.glsl):
//   L_N = L_K + (L_K − L_(K−1)) · u_tail   (rgb; u_tail from the face flux)
// in place on L_K; the coverage α is kept. Run once per face direction.
#include "common/bounce_tail.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_previous;                         // this face of L_(K−1)
layout(rgba32f, binding = 0) uniform image3D u_face;  // this face of L_K, extrapolated in place
uniform ivec3 u_grid_size;
uniform vec3 u_tail;

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 current = imageLoad(u_face, v);
    if (current == vec4(0.0)) return;  // an empty voxel: light only accumulates, so L_(K−1) is 0 there too
    vec3 previous = texelFetch(u_previous, v, 0).rgb;
    imageStore(u_face, v, vec4(bounce_tail(current.rgb, current.rgb - previous, u_tail), current.a));
}
