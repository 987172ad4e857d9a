// SPDX-License-Identifier: GPL-3.0-or-later
// Octree LPV downsampling (Olovsson and Doggett 2013, §3.2, Eq. 2): O_i(x) from the eight elements
// O_{i-1}([2x, 2x+1], ...).
// Eq. 2 averages, to keep "a uniform range of light intensities" across levels for a state that is a density.
// Our state is extensive: a cell's SH coefficients are the radiant intensity (W/sr) of all the light in that cell
// (flux = c0·2√π, lpv/common.glsl), and propagation moves that flux cell to cell. The light in a parent cell is the
// light in its eight children, so the parent's intensity is their SUM — which is Eq. 2's average applied to the
// density (flux per volume): Φ_parent/V_parent = Σ Φ_child/(8·V_child) = mean of the child densities. Summing keeps
// the total flux of every level identical to O_0's (tested). Children beyond an odd-sized level are empty.
#include "lpv/common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_src_r;       // O_{i-1}, after injection (never after propagation: §3.2, a separate step)
uniform sampler3D u_src_g;
uniform sampler3D u_src_b;
uniform ivec3 u_src_size;
uniform ivec3 u_dst_size;
layout(rgba32f, binding = 0) uniform writeonly image3D u_dst_r;
layout(rgba32f, binding = 1) uniform writeonly image3D u_dst_g;
layout(rgba32f, binding = 2) uniform writeonly image3D u_dst_b;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, u_dst_size))) return;
    vec4 r = vec4(0.0), g = vec4(0.0), b = vec4(0.0);
    for (int k = 0; k < 8; ++k) {
        ivec3 c = 2 * p + ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        if (any(greaterThanEqual(c, u_src_size))) continue;
        r += texelFetch(u_src_r, c, 0);
        g += texelFetch(u_src_g, c, 0);
        b += texelFetch(u_src_b, c, 0);
    }
    imageStore(u_dst_r, p, r);
    imageStore(u_dst_g, p, g);
    imageStore(u_dst_b, p, b);
}
