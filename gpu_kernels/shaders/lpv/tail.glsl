// SPDX-License-Identifier: GPL-3.0-or-later
// The extrapolated bounce tail of the gathered transport (lpv/gather.py gather_all): bounces K+1 … N without
// gathering them, as the last gathered pass's irradiance times u_tail (r = the flux ratio of the next bounce's VPLs
// to the last one's; common/bounce_tail.glsl).
#include "common/bounce_tail.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
layout(rgba32f, binding = 0) uniform readonly image3D u_front;  // the last gathered pass
layout(rgba32f, binding = 1) uniform readonly image3D u_back;
layout(rgba32f, binding = 2) uniform image3D u_front_total;
layout(rgba32f, binding = 3) uniform image3D u_back_total;
uniform ivec3 u_size;
uniform vec3 u_tail;

void main() {
    ivec3 f = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(f, u_size))) return;
    vec4 front = imageLoad(u_front_total, f);
    if (front.a <= 0.0) return;  // not a surface voxel
    imageStore(u_front_total, f, vec4(bounce_tail(front.rgb, imageLoad(u_front, f).rgb, u_tail), front.a));
    vec4 back = imageLoad(u_back_total, f);
    imageStore(u_back_total, f, vec4(bounce_tail(back.rgb, imageLoad(u_back, f).rgb, u_tail), back.a));
}
