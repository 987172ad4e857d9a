// One more bounce (issue: multiple bounces): every surface voxel reflects the light it absorbed in the last pass,
// Φ = albedo × E × area per side, as a Lambertian VPL (Φ/π)·lobe(±n) half a cell in front of that side —
// the same injection as an RSM texel (lpv_inject.glsl), so the next propagation carries the next bounce.
#include "lpv_common.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(std430, binding = 4) buffer LpvAccum { int accum[]; };
uniform sampler3D u_front;          // last pass: irradiance of each fine voxel's front / back side
uniform sampler3D u_back;
uniform sampler3D u_voxel_normal;
uniform sampler3D u_voxel_area;
uniform sampler3D u_voxel_albedo;
uniform vec3 u_fine_origin;
uniform ivec3 u_fine_size;
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform ivec3 u_grid_size;
uniform float u_fixed_scale;

const float PI = 3.14159265358979;

void add_fixed(int base, vec4 c) {
    atomicAdd(accum[base + 0], int(round(c.x * u_fixed_scale)));
    atomicAdd(accum[base + 1], int(round(c.y * u_fixed_scale)));
    atomicAdd(accum[base + 2], int(round(c.z * u_fixed_scale)));
    atomicAdd(accum[base + 3], int(round(c.w * u_fixed_scale)));
}

void emit(LpvGrid g, vec3 p, vec3 n, vec3 flux) {
    if (max(flux.r, max(flux.g, flux.b)) <= 0.0) return;
    ivec3 c = lpv_cell(g, p + n * 0.5 * g.cell);
    if (!lpv_inside(g, c)) return;
    vec4 lobe = sh_clamped_cosine(n) / PI;
    int base = lpv_index(g, c) * 12;
    add_fixed(base + 0, lobe * flux.r);
    add_fixed(base + 4, lobe * flux.g);
    add_fixed(base + 8, lobe * flux.b);
}

void main() {
    ivec3 f = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(f, u_fine_size))) return;
    float area = texelFetch(u_voxel_area, f, 0).a;
    vec3 nv = texelFetch(u_voxel_normal, f, 0).xyz;
    if (area <= 0.0 || dot(nv, nv) == 0.0) return;
    nv = normalize(nv);
    vec3 albedo = texelFetch(u_voxel_albedo, f, 0).rgb;
    vec3 p = u_fine_origin + (vec3(f) + 0.5) * (0.5 * u_grid_cell);
    LpvGrid g = LpvGrid(u_grid_origin, u_grid_cell, u_grid_size);
    emit(g, p, nv, albedo * texelFetch(u_front, f, 0).rgb * area);
    emit(g, p, -nv, albedo * texelFetch(u_back, f, 0).rgb * area);
}
