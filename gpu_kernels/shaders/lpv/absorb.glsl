// SPDX-License-Identifier: GPL-3.0-or-later
// Absorbed light per surface voxel: where does the flux that fuzzy occlusion stops go? (Energy-exact LPV lookup.)
// Propagation stops the fraction B of the flux crossing a face (lpv/propagate.glsl), where B sums the projected
// area of the surfaces inside the cell-sized box centred on that face — eight fine voxels of half the cell size
// (lpv.face_blocking). Each of those voxels takes its share of the stopped flux, proj_a(voxel) / Σ proj_a, on the
// side of its surfaces that faces the cell the light came from. Divided by the voxel's surface area, this is the
// irradiance of its front and back sides; summed over all voxels, irradiance × area is exactly the flux the
// geometry absorbed, which — propagation conserving flux — is the injected flux minus what left the grid.
#include "lpv/common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
layout(std430, binding = 6) readonly buffer FaceFlux { vec4 face_flux[]; };
uniform sampler3D u_geometry;       // per LPV cell (size + 1): blocked fraction of its lower x/y/z faces
uniform sampler3D u_voxel_normal;   // fine voxels: mean sign-canonical normal
uniform sampler3D u_voxel_area;     // fine voxels: rgb projected area on the x/y/z planes, a = surface area (m²)
uniform ivec3 u_grid_size;          // LPV cells; fine voxels are 2·size + 2, offset by −cell/2
uniform float u_grid_cell;
layout(rgba32f, binding = 0) uniform writeonly image3D u_front;  // this bounce: rgb irradiance (W/m²), a = 1 if surface
layout(rgba32f, binding = 1) uniform writeonly image3D u_back;
layout(rgba32f, binding = 2) uniform image3D u_front_total;      // summed over bounces (what lighting reads)
layout(rgba32f, binding = 3) uniform image3D u_back_total;

void main() {
    ivec3 f = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(f, 2 * u_grid_size + 2))) return;
    vec4 area = texelFetch(u_voxel_area, f, 0);
    vec3 nv = texelFetch(u_voxel_normal, f, 0).xyz;
    if (area.a <= 0.0 || dot(nv, nv) == 0.0) {
        imageStore(u_front, f, vec4(0.0));
        imageStore(u_back, f, vec4(0.0));
        imageStore(u_front_total, f, vec4(0.0));
        imageStore(u_back_total, f, vec4(0.0));
        return;
    }
    nv = normalize(nv);
    LpvGrid grid = LpvGrid(vec3(0.0), 1.0, u_grid_size);
    vec3 centre = (vec3(f) + 0.5) * 0.5 - 0.5;  // fine voxel centre in LPV grid units
    vec3 front = vec3(0.0), back = vec3(0.0);
    for (int a = 0; a < 3; ++a) {
        if (area[a] <= 0.0) continue;
        // The face whose box holds this voxel: lower face (normal a) of cell c.
        ivec3 c;
        for (int i = 0; i < 3; ++i) c[i] = i == a ? f[i] >> 1 : (f[i] - 1) >> 1;
        if (any(lessThan(c, ivec3(0))) || any(greaterThan(c, u_grid_size))) continue;
        float blocked = texelFetch(u_geometry, c, 0)[a];
        if (blocked <= 0.0) continue;
        float share = area[a] / (blocked * u_grid_cell * u_grid_cell);  // = proj_a / Σ proj_a unless the face is saturated
        share = min(share, 1.0);
        ivec3 e = ivec3(0);
        e[a] = 1;
        for (int s = 0; s < 2; ++s) {
            // Along +a light enters c through this face; along −a it enters c − e_a through its upper face.
            ivec3 cell = s == 0 ? c : c - e;
            ivec3 source = s == 0 ? c - e : c;
            if (!lpv_inside(grid, cell)) continue;
            vec3 flux = face_flux[lpv_index(grid, cell) * 6 + 2 * a + s].rgb;
            vec3 absorbed = flux * blocked * share;
            if (dot(vec3(source) + 0.5 - centre, nv) > 0.0) front += absorbed; else back += absorbed;
        }
    }
    front /= area.a;
    back /= area.a;
    imageStore(u_front, f, vec4(front, 1.0));
    imageStore(u_back, f, vec4(back, 1.0));
#if defined(MODE_ADD)
    front += imageLoad(u_front_total, f).rgb;
    back += imageLoad(u_back_total, f).rgb;
#endif
    imageStore(u_front_total, f, vec4(front, 1.0));
    imageStore(u_back_total, f, vec4(back, 1.0));
}
