// SPDX-License-Identifier: GPL-3.0-or-later
// The compute pass after voxelisation (Freed 2018, §4.1; voxel/voxelize.py zeroes the accumulators before it):
// MODE_RESOLVE turns their integer sums (voxel/common.glsl) into the RGBA32F volumes:
//   area     rgb = Σ A|n.x|, Σ A|n.y|, Σ A|n.z| (m²), a = Σ A (m²)
//   albedo   rgb = Σ A·albedo / Σ A, a = opacity = min(1, max projected area / cell²)
//   normal   xyz = Σ A·n̂ / Σ A with n̂ sign-canonicalised (not renormalised: |mean| < 1 says normals disagree)
//   emission rgb = Σ A·emission / Σ A
//   with SIDES, albedo rgb is the mean over the pieces seen from the front side only (voxel/common.glsl) and a fifth
//   volume, albedo_back, the back side's (rgb; a = the same opacity)
//   with POSITIONS, position rgb = Σ A·(centroid − voxel min corner) / Σ A, in cells, and extent_lo / extent_hi
//   the box the surfaces span, likewise; normal w = Σ ±A / Σ A, + for a piece facing along the canonical normal
//   (1: all face that way, −1: all the other, near 0: both, as a slab's two faces)
// Pure integer→float arithmetic per voxel: deterministic.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform ivec3 u_grid_size;

#if defined(MODE_RESOLVE)
uniform usampler3D u_acc_area;
uniform usampler3D u_acc_albedo;
uniform usampler3D u_acc_normal;
uniform usampler3D u_acc_emission;
uniform float u_unit_area;       // m² per fixed-point unit of area = cell² / 2^scale_bits
uniform float u_cell_area;       // cell² (m²)
uniform float u_albedo_max;
uniform float u_emission_max;
layout(binding = 0, rgba32f) uniform writeonly image3D u_area;
layout(binding = 1, rgba32f) uniform writeonly image3D u_albedo;
layout(binding = 2, rgba32f) uniform writeonly image3D u_normal;
layout(binding = 3, rgba32f) uniform writeonly image3D u_emission;
#if defined(SIDES)
uniform usampler3D u_acc_albedo_back;
layout(binding = 4, rgba32f) uniform writeonly image3D u_albedo_back;

// Mean albedo over the area a side sees (.w); 0 where it sees none.
vec3 side_albedo(uvec4 acc) {
    return acc.w > 0u ? vec3(acc.rgb) * (u_albedo_max / float(acc.w)) : vec3(0.0);
}
#endif
#if defined(POSITIONS)
uniform usampler3D u_acc_position;
// rgb: the surfaces' area-weighted centroid, in cells from the voxel's min corner; extent_lo / extent_hi rgb: the
// box the surfaces span, likewise (all 0 where empty, like every volume)
layout(binding = 5, rgba32f) uniform writeonly image3D u_position;
layout(binding = 6, rgba32f) uniform writeonly image3D u_extent_lo;
layout(binding = 7, rgba32f) uniform writeonly image3D u_extent_hi;
#endif

uvec4 fetch(usampler3D s, ivec3 v) {
    ivec3 t = ivec3(4 * v.x, v.y, v.z);
    return uvec4(texelFetch(s, t, 0).r, texelFetch(s, t + ivec3(1, 0, 0), 0).r,
                 texelFetch(s, t + ivec3(2, 0, 0), 0).r, texelFetch(s, t + ivec3(3, 0, 0), 0).r);
}

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    // Most voxels are empty: one fetch decides, and an empty one keeps the zeros its volumes were made with
    // (voxelize._resolve: llvmpipe's image stores are slow, and most of the grid would store zeros).
    if (texelFetch(u_acc_area, ivec3(4 * v.x + 3, v.y, v.z), 0).r == 0u) return;
    uvec4 area = fetch(u_acc_area, v);
    vec4 area_m2 = vec4(area) * u_unit_area;
    float inv = 1.0 / float(area.w);   // the fixed-point unit cancels in every mean
    vec4 albedo = vec4(vec3(fetch(u_acc_albedo, v).rgb) * (inv * u_albedo_max),
                       min(1.0, max(max(area_m2.x, area_m2.y), area_m2.z) / u_cell_area));
    vec4 normal = vec4(vec3(ivec3(fetch(u_acc_normal, v).xyz)) * (2.0 * inv), 0.0);
    vec4 emission = vec4(vec3(fetch(u_acc_emission, v).rgb) * (inv * u_emission_max), 0.0);
#if defined(SIDES)
    albedo.rgb = side_albedo(fetch(u_acc_albedo, v));
    vec4 back = vec4(side_albedo(fetch(u_acc_albedo_back, v)), albedo.a);
#endif
#if defined(POSITIONS)
    vec4 position = vec4(vec3(fetch(u_acc_position, v).xyz) * inv, 0.0);
    normal.w = float(int(fetch(u_acc_normal, v).w)) * (2.0 * inv);
    vec4 extent_lo = vec4(1.0 - vec3(fetch(u_acc_position, v + ivec3(0, u_grid_size.y, 0)).xyz) / 65535.0, 0.0);
    vec4 extent_hi = vec4(vec3(fetch(u_acc_position, v + ivec3(0, 2 * u_grid_size.y, 0)).xyz) / 65535.0, 0.0);
#endif
    imageStore(u_area, v, area_m2);
    imageStore(u_albedo, v, albedo);
    imageStore(u_normal, v, normal);
    imageStore(u_emission, v, emission);
#if defined(SIDES)
    imageStore(u_albedo_back, v, back);
#endif
#if defined(POSITIONS)
    imageStore(u_position, v, position);
    imageStore(u_extent_lo, v, extent_lo);
    imageStore(u_extent_hi, v, extent_hi);
#endif
}
#endif
