// SPDX-License-Identifier: GPL-3.0-or-later
// World (sky) light enters the LPV through the open faces of the grid's border (issue: world light). A constant
// world radiance L_w crossing a face of area s² over a hemisphere carries flux π·L_w·s² inward; it is injected into
// the border cell as a Lambertian lobe about the inward normal, (Φ/π)·lobe = L_w·s²·lobe, times the fraction of
// that face geometry leaves open. Propagation then carries it in, and fuzzy occlusion shades it.
#include "lpv/fixed.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
uniform sampler3D u_geometry;   // blocked fraction of each cell's lower x/y/z faces (size + 1)
uniform bool u_occlusion;
uniform vec3 u_world;           // world radiance (colour × strength)
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform ivec3 u_grid_size;

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, u_grid_size))) return;
    LpvGrid g = LpvGrid(u_grid_origin, u_grid_cell, u_grid_size);
    for (int a = 0; a < 3; ++a) {
        for (int s = 0; s < 2; ++s) {
            // s = 0: the lower border (light enters along +a); s = 1: the upper border (along −a).
            if ((s == 0 && c[a] != 0) || (s == 1 && c[a] != u_grid_size[a] - 1)) continue;
            ivec3 face = c;
            if (s == 1) face[a] += 1;  // the upper face of c is the lower face of c + e_a
            float open = u_occlusion ? 1.0 - texelFetch(u_geometry, face, 0)[a] : 1.0;
            vec3 n = vec3(0.0);
            n[a] = s == 0 ? 1.0 : -1.0;
            vec4 lobe = sh_clamped_cosine(n) * u_grid_cell * u_grid_cell * open;
            int base = lpv_index(g, c) * 12;
            add_fixed(base + 0, lobe * u_world.r);
            add_fixed(base + 4, lobe * u_world.g);
            add_fixed(base + 8, lobe * u_world.b);
        }
    }
}
