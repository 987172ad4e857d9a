// SPDX-License-Identifier: GPL-3.0-or-later
// One more bounce (issue: multiple bounces): every surface voxel reflects the light it absorbed in the last pass,
// Φ = albedo × E × area per side, as a Lambertian VPL (Φ/π)·lobe(±n) half a cell in front of that side —
// the same injection as an RSM texel (lpv/inject.glsl), so the next propagation carries the next bounce.
#include "lpv/fixed.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_front;          // last pass: irradiance of each fine voxel's front / back side
uniform sampler3D u_back;
uniform sampler3D u_voxel_normal;
uniform sampler3D u_voxel_area;
uniform sampler3D u_voxel_albedo;        // the front side's albedo (voxel/voxelize.py sides=True)
uniform sampler3D u_voxel_albedo_back;   // the back side's
uniform vec3 u_fine_origin;
uniform ivec3 u_fine_size;
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform ivec3 u_grid_size;

void main() {
    ivec3 f = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(f, u_fine_size))) return;
    float area = texelFetch(u_voxel_area, f, 0).a;
    vec3 nv = texelFetch(u_voxel_normal, f, 0).xyz;
    if (area <= 0.0 || dot(nv, nv) == 0.0) return;
    nv = normalize(nv);
    vec3 p = u_fine_origin + (vec3(f) + 0.5) * (0.5 * u_grid_cell);
    LpvGrid g = LpvGrid(u_grid_origin, u_grid_cell, u_grid_size);
    inject_lambertian(g, p, nv, texelFetch(u_voxel_albedo, f, 0).rgb * texelFetch(u_front, f, 0).rgb * area);
    inject_lambertian(g, p, -nv, texelFetch(u_voxel_albedo_back, f, 0).rgb * texelFetch(u_back, f, 0).rgb * area);
}
