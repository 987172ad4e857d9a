// SPDX-License-Identifier: GPL-3.0-or-later
// Tessellation-based surface voxelisation (Freed 2018, §4.1.2; Fei et al. 2012): no rasterisation.
//
// The control shader picks tessellation levels from the triangle's size in voxels so that every generated
// sub-triangle is smaller than a voxel (1/u_supersample of one); the evaluation shader places the generated
// vertices on the triangle; a geometry shader takes each sub-triangle and writes it, as a point at its centroid,
// into the voxel containing that centroid, with its exact area (the sub-triangles tile the patch, so their
// areas sum to the triangle's). The rasteriser is switched off (GL_RASTERIZER_DISCARD); nothing is emitted.
// Triangles that would need more than u_max_level are split on the CPU first (voxel/voxelize.py), as Freed's §4.1.2 and
// footnote 3 of §5.2.2 suggest.
// Stage macros TESS_CONTROL_SHADER / TESS_EVALUATION_SHADER are injected by voxel/voxelize.py.
#if defined(VERTEX_SHADER)
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;
uniform vec3 u_grid_origin;
uniform float u_inv_cell;
out vec3 v_grid;
out vec2 v_uv;
void main() {
    v_grid = (in_position - u_grid_origin) * u_inv_cell;   // grid units
    v_uv = in_uv;
}
#endif

#if defined(TESS_CONTROL_SHADER)
layout(vertices = 3) out;
in vec3 v_grid[];
in vec2 v_uv[];
out vec3 c_grid[];
out vec2 c_uv[];
patch out vec3 c_normal;      // unit geometric normal
patch out float c_area;       // triangle area in cell²
uniform float u_supersample;  // sub-triangles ≤ 1/u_supersample voxel across
uniform float u_max_level;    // GL_MAX_TESS_GEN_LEVEL (64 is the GL minimum)

float level(float cells) { return clamp(ceil(cells * u_supersample), 1.0, u_max_level); }

void main() {
    c_grid[gl_InvocationID] = v_grid[gl_InvocationID];
    c_uv[gl_InvocationID] = v_uv[gl_InvocationID];
    if (gl_InvocationID == 0) {
        vec3 n = cross(v_grid[1] - v_grid[0], v_grid[2] - v_grid[0]);
        float len = length(n);
        c_area = 0.5 * len;
        c_normal = len > 0.0 ? n / len : vec3(0.0, 0.0, 1.0);
        // §4.1.2: the outer level of an edge is how many voxels it spans; outer[i] is the edge opposite vertex i.
        float l0 = level(length(v_grid[2] - v_grid[1]));
        float l1 = level(length(v_grid[0] - v_grid[2]));
        float l2 = level(length(v_grid[1] - v_grid[0]));
        gl_TessLevelOuter[0] = l0;
        gl_TessLevelOuter[1] = l1;
        gl_TessLevelOuter[2] = l2;
        // §4.1.2 sets the inner level from the largest altitude h_max; every altitude is ≤ the longest edge, and
        // using the longest edge keeps sub-triangles of a thin sliver short along it too (h_max alone leaves
        // sub-triangles as long as the sliver). A zero-area patch gets level 0 and is culled.
        gl_TessLevelInner[0] = len > 0.0 ? max(max(l0, l1), l2) : 0.0;
        if (!(len > 0.0)) gl_TessLevelOuter[0] = 0.0;
    }
}
#endif

#if defined(TESS_EVALUATION_SHADER)
layout(triangles, equal_spacing, ccw) in;
in vec3 c_grid[];
in vec2 c_uv[];
patch in vec3 c_normal;
patch in float c_area;
out vec3 e_grid;
out vec2 e_uv;
out vec2 e_bary;      // (u, v) of gl_TessCoord: sub-triangle areas are computed in this exact domain
flat out vec3 e_normal;
flat out float e_area;
void main() {
    vec3 b = gl_TessCoord;
    e_grid = b.x * c_grid[0] + b.y * c_grid[1] + b.z * c_grid[2];
    e_uv = b.x * c_uv[0] + b.y * c_uv[1] + b.z * c_uv[2];
    e_bary = b.xy;
    e_normal = c_normal;
    e_area = c_area;
}
#endif

#if defined(GEOMETRY_SHADER)
#include "voxel/common.glsl"
layout(triangles) in;
layout(points, max_vertices = 1) out;
in vec3 e_grid[];
in vec2 e_uv[];
in vec2 e_bary[];
flat in vec3 e_normal[];
flat in float e_area[];
void main() {
    // Share of the patch: |det| of the sub-triangle in the (u, v) domain, whose full triangle has |det| = 1.
    vec2 d1 = e_bary[1] - e_bary[0], d2 = e_bary[2] - e_bary[0];
    float share = abs(d1.x * d2.y - d1.y * d2.x);
    vec3 c = (e_grid[0] + e_grid[1] + e_grid[2]) / 3.0;
    vec2 uv = (e_uv[0] + e_uv[1] + e_uv[2]) / 3.0;
    deposit(ivec3(floor(c)), share * e_area[0], e_normal[0], voxel_albedo(uv));
}
#endif
