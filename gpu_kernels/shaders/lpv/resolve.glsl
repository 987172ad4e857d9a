// SPDX-License-Identifier: GPL-3.0-or-later
// Fixed-point injection sums (12 ints per cell) → three RGBA32F volumes of SH coefficients (red, green, blue).
// MODE_ADD adds the injected light to what the volumes already hold (used by world light and bounces).
#include "lpv/common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
layout(std430, binding = 4) readonly buffer LpvAccum { int accum[]; };
layout(rgba32f, binding = 0) uniform image3D u_out_r;
layout(rgba32f, binding = 1) uniform image3D u_out_g;
layout(rgba32f, binding = 2) uniform image3D u_out_b;
uniform ivec3 u_grid_size;
uniform float u_fixed_scale;

vec4 load(int base) {
    return vec4(accum[base], accum[base + 1], accum[base + 2], accum[base + 3]) / u_fixed_scale;
}

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, u_grid_size))) return;
    int base = ((c.z * u_grid_size.y + c.y) * u_grid_size.x + c.x) * 12;
    vec4 r = load(base), g = load(base + 4), b = load(base + 8);
#if defined(MODE_ADD)
    r += imageLoad(u_out_r, c);
    g += imageLoad(u_out_g, c);
    b += imageLoad(u_out_b, c);
#endif
    imageStore(u_out_r, c, r);
    imageStore(u_out_g, c, g);
    imageStore(u_out_b, c, b);
}
