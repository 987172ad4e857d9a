// SPDX-License-Identifier: GPL-3.0-or-later
// Octree LPV merge (Olovsson and Doggett 2013, §3.4): M(x) = S(x), one O_0-sized volume that the unchanged
// lighting step reads.
// S (Eq. 1): I(x) = min_i I_i(x >> i) over the index hierarchy (§3.1), then sample O_{I(x)}(x >> I(x)).
//
// What is merged is each level's ACCUMULATED intensity A_i (injected + every propagation step), which Kaplanyan's
// lookup turns into irradiance as E = A·lobe/cell_i² (lpv/lighting.glsl): A/cell² is a radiance, the quantity that
// must be uniform across levels (the paper's "uniform range of light intensities"). A level-i cell is 2^i O_0 cells
// wide, so an O_0 cell gets A_i / 4^i: then A/cell_0² = A_i/cell_i², the level's own radiance. (Per photon: light
// crossing a parent cell adds its intensity once to A_i; crossing the same region at O_0 it adds it once in each of
// the 2^i children on its path, i.e. 2^i/8^i = 1/4^i per child on average. The injected light, counted once in its
// cell, shares 1/8^i instead: lpv/octree.propagate_levels starts A_i with J_i/2^i.) The flux lookup cannot be used
// on M: every level holds ALL the injected light, and the flux a surface absorbs is a sum over the whole propagation
// history of one grid, which a per-cell choice of level does not have.
#include "lpv/common.glsl"

#define MAX_LEVELS 5
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_level_r[MAX_LEVELS];  // A_i per level (RGB SH)
uniform sampler3D u_level_g[MAX_LEVELS];
uniform sampler3D u_level_b[MAX_LEVELS];
uniform sampler3D u_index[MAX_LEVELS];    // I_i: the level to sample, per level-i node (float-coded integers)
uniform int u_levels;
uniform ivec3 u_grid_size;                // O_0
layout(rgba32f, binding = 0) uniform writeonly image3D u_out_r;
layout(rgba32f, binding = 1) uniform writeonly image3D u_out_g;
layout(rgba32f, binding = 2) uniform writeonly image3D u_out_b;
layout(r32f, binding = 3) uniform writeonly image3D u_out_index;  // I(x), flattened (diagnostics and tests)

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, u_grid_size))) return;
    int level = u_levels - 1;
    for (int i = 0; i < MAX_LEVELS; ++i) {
        if (i >= u_levels) break;
        level = min(level, int(texelFetch(u_index[i], c >> i, 0).r + 0.5));
    }
    vec4 r = vec4(0.0), g = vec4(0.0), b = vec4(0.0);
    for (int i = 0; i < MAX_LEVELS; ++i) {  // constant indices into the sampler arrays (GLSL 4.3 needs uniform ones)
        if (i != level) continue;
        ivec3 p = c >> i;
        r = texelFetch(u_level_r[i], p, 0);
        g = texelFetch(u_level_g[i], p, 0);
        b = texelFetch(u_level_b[i], p, 0);
    }
    float scale = 1.0 / float(1 << (2 * level));  // 1/4^i (see above)
    imageStore(u_out_r, c, r * scale);
    imageStore(u_out_g, c, g * scale);
    imageStore(u_out_b, c, b * scale);
    imageStore(u_out_index, c, vec4(float(level)));
}
