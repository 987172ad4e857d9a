// SPDX-License-Identifier: GPL-3.0-or-later
// Shared by voxel/raster.glsl and voxel/tess.glsl: material inputs and the fixed-point deposit of one
// surface piece into the voxel accumulators (Freed 2018, §4.1: "we average the resulting color value using atomic
// operations"). There are no float atomics in GL 4.5, so every quantity is summed as an integer: uint atomics
// commute, so the sums, and the resolve that divides them, are bit-identical whatever order fragments arrive in.
//
// Accumulators: four r32ui 3D images of (4·nx, ny, nz); channel c of voxel (x, y, z) lives at (4x + c, y, z) so
// one piece's adds touch neighbouring texels. Fixed point: 1 unit = 2^-scale_bits cell² of area, u_fixed_scale =
// 2^scale_bits (voxel/voxelize.py picks the bits and re-runs with fewer if a voxel's total wraps, see u_flags).
//   acc_area:     A|n.x|, A|n.y|, A|n.z|, A            (unsigned)
//   acc_albedo:   A·albedo.rgb / u_albedo_max          (unsigned; .w unused)
//   acc_normal:   A·n.xyz / 2                          (two's complement int in a uint; |Σ A n/2| < 2^31)
//                 .w with POSITIONS: ±A / 2, + where n is its own canonical normal (the facing, same bound)
//   acc_emission: A·emission.rgb / u_emission_max      (unsigned; .w unused)
// With SIDES (voxel/voxelize.py sides=True) the albedo is kept per side of the voxel: acc_albedo holds what the
// side its canonical normals point to sees (.w: the area seen from there), acc_albedo_back the other side's.
// With POSITIONS (voxel/voxelize.py positions=True) acc_position, (4·nx, 3·ny, nz), holds in its rows [0, ny)
// A·(the piece's centroid − the voxel's min corner, in cells), so the voxel's surfaces have an area-weighted
// centroid, and in rows [ny, 2ny) and [2ny, 3ny) the largest 1 − (its lowest corner) and highest corner, in
// 1/65535 of a cell (atomic max from zero): the box its surfaces span inside the voxel.
// Every channel is rounded from a value ≤ the area value, and rounding is monotone, so no channel can exceed
// the total-area channel: checking that one channel for wrap-around guards them all.
#pragma once

uniform vec3 u_base_color;       // linear RGB, the diffuse albedo when no texture
uniform vec3 u_albedo_scale;     // common/principled.py: transport_albedo, albedo = base ⊙ scale + offset
uniform vec3 u_albedo_offset;
uniform vec3 u_emission;         // emission colour × strength
uniform bool u_use_texture;
uniform sampler2D u_base_texture;
uniform float u_albedo_max;      // > 0: largest albedo component in the scene (normalises the albedo channel)
uniform float u_emission_max;    // > 0: largest emission component in the scene
uniform float u_fixed_scale;     // 2^scale_bits: fixed-point units per cell² of area

layout(binding = 0, r32ui) uniform uimage3D u_acc_area;
layout(binding = 1, r32ui) uniform uimage3D u_acc_albedo;
layout(binding = 2, r32ui) uniform uimage3D u_acc_normal;
layout(binding = 3, r32ui) uniform uimage3D u_acc_emission;
layout(binding = 4, r32ui) uniform uimage3D u_flags;   // 1×1×1; bit 0 set when an area sum wrapped
#if defined(SIDES)
layout(binding = 5, r32ui) uniform uimage3D u_acc_albedo_back;
#endif
#if defined(POSITIONS)
layout(binding = 7, r32ui) uniform uimage3D u_acc_position;
#endif
uniform ivec3 u_grid_size;            // grid size (nx, ny, nz)
// The accumulators hold the voxels u_region_lo … u_region_lo + u_region_size − 1: all of them (0, u_grid_size), or
// the part an object's move changed (voxelize's `region`); coordinates stay the whole grid's, so a voxel of the
// part sums exactly what it sums in a voxelisation of the whole grid.
uniform ivec3 u_region_lo;
uniform ivec3 u_region_size;

// Albedo of a voxel surfel: what the surface reflects of the light reaching it, averaged over directions
// (cosine-weighted), its glossy layers' share included (common/principled.py: transport_albedo): a voxel has no
// view direction, so the glossy reflection leaves it diffusely.
vec3 voxel_albedo(vec2 uv) {
    vec3 color = u_use_texture ? textureLod(u_base_texture, uv, 0.0).rgb : u_base_color;
    return max(color, vec3(0.0)) * u_albedo_scale + u_albedo_offset;
}

// Two-sided surfaces: flip a normal so its largest-magnitude component is positive (ties: first axis wins).
vec3 canonical_normal(vec3 n) {
    vec3 a = abs(n);
    float lead = (a.x >= a.y && a.x >= a.z) ? n.x : (a.y >= a.z ? n.y : n.z);
    return lead < 0.0 ? -n : n;
}

#define MIN_PIECE_UNITS 64.0
uint fixed_round(float x) { return uint(x + 0.5); }   // x ≥ 0; monotone, so channel ≤ area channel holds

// Add one surface piece of `area_cells` (area in cell² units) with unit normal `n`, centroid offset.xyz and box
// [lo, hi] (cells from the voxel's min corner) to voxel `v`; `seen`: whether its side along canonical_normal(n)
// (x) and its other side (y) are uncovered (SIDES only: voxel/raster.glsl).
void deposit_seen(ivec3 v, float area_cells, vec3 n, vec3 albedo, bvec2 seen, vec3 offset, vec3 lo, vec3 hi) {
    ivec3 r = v - u_region_lo;   // the accumulators' voxel
    if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, u_grid_size)) || any(lessThan(r, ivec3(0))) ||
        any(greaterThanEqual(r, u_region_size)) || !(area_cells > 0.0)) return;
    // A piece with positive area counts at least MIN_PIECE_UNITS, so occupancy (area > 0) never loses a voxel a
    // surface really crosses and a voxel holding only slivers still gets a mean albedo/normal to 1/64; the bias
    // is < 64 units (2^-18 cell² at 24 bits) per sliver piece, and none for pieces larger than that.
    float a = max(area_cells * u_fixed_scale, MIN_PIECE_UNITS);
    uint a_fix = fixed_round(a);
    ivec3 t = ivec3(4 * r.x, r.y, r.z);
    uint before = imageAtomicAdd(u_acc_area, t + ivec3(3, 0, 0), a_fix);
    if (before > 0xFFFFFFFFu - a_fix) imageAtomicOr(u_flags, ivec3(0), 1u);
    vec3 na = abs(n);
    imageAtomicAdd(u_acc_area, t, fixed_round(a * na.x));
    imageAtomicAdd(u_acc_area, t + ivec3(1, 0, 0), fixed_round(a * na.y));
    imageAtomicAdd(u_acc_area, t + ivec3(2, 0, 0), fixed_round(a * na.z));
    vec3 alb = a * min(albedo / u_albedo_max, vec3(1.0));
#if defined(SIDES)
    if (seen.x) {
        imageAtomicAdd(u_acc_albedo, t + ivec3(3, 0, 0), a_fix);
        imageAtomicAdd(u_acc_albedo, t, fixed_round(alb.r));
        imageAtomicAdd(u_acc_albedo, t + ivec3(1, 0, 0), fixed_round(alb.g));
        imageAtomicAdd(u_acc_albedo, t + ivec3(2, 0, 0), fixed_round(alb.b));
    }
    if (seen.y) {
        imageAtomicAdd(u_acc_albedo_back, t + ivec3(3, 0, 0), a_fix);
        imageAtomicAdd(u_acc_albedo_back, t, fixed_round(alb.r));
        imageAtomicAdd(u_acc_albedo_back, t + ivec3(1, 0, 0), fixed_round(alb.g));
        imageAtomicAdd(u_acc_albedo_back, t + ivec3(2, 0, 0), fixed_round(alb.b));
    }
#else
    imageAtomicAdd(u_acc_albedo, t, fixed_round(alb.r));
    imageAtomicAdd(u_acc_albedo, t + ivec3(1, 0, 0), fixed_round(alb.g));
    imageAtomicAdd(u_acc_albedo, t + ivec3(2, 0, 0), fixed_round(alb.b));
#endif
#if defined(POSITIONS)
    vec3 at = a * clamp(offset, vec3(0.0), vec3(1.0));
    uvec3 below = uvec3((1.0 - clamp(lo, vec3(0.0), vec3(1.0))) * 65535.0 + 0.5);
    uvec3 above = uvec3(clamp(hi, vec3(0.0), vec3(1.0)) * 65535.0 + 0.5);
    ivec3 row = ivec3(0, u_region_size.y, 0);
    for (int c = 0; c < 3; ++c) {
        imageAtomicAdd(u_acc_position, t + ivec3(c, 0, 0), fixed_round(at[c]));
        imageAtomicMax(u_acc_position, t + ivec3(c, 0, 0) + row, below[c]);
        imageAtomicMax(u_acc_position, t + ivec3(c, 0, 0) + 2 * row, above[c]);
    }
#endif
    vec3 c = canonical_normal(n) * (0.5 * a);
    imageAtomicAdd(u_acc_normal, t, uint(int(round(c.x))));
    imageAtomicAdd(u_acc_normal, t + ivec3(1, 0, 0), uint(int(round(c.y))));
    imageAtomicAdd(u_acc_normal, t + ivec3(2, 0, 0), uint(int(round(c.z))));
#if defined(POSITIONS)
    // Which way the pieces face, which the canonical normal forgets: a closed box's wall faces out of it, so the
    // floor it stands on is known to lie on its outer side (lpv/wall_sides.py).
    imageAtomicAdd(u_acc_normal, t + ivec3(3, 0, 0), uint(int(round(dot(c, n) > 0.0 ? 0.5 * a : -0.5 * a))));
#endif
    if (u_emission_max > 0.0) {
        vec3 e = a * min(max(u_emission, vec3(0.0)) / u_emission_max, vec3(1.0));
        imageAtomicAdd(u_acc_emission, t, fixed_round(e.r));
        imageAtomicAdd(u_acc_emission, t + ivec3(1, 0, 0), fixed_round(e.g));
        imageAtomicAdd(u_acc_emission, t + ivec3(2, 0, 0), fixed_round(e.b));
    }
}

void deposit(ivec3 v, float area_cells, vec3 n, vec3 albedo) {
    deposit_seen(v, area_cells, n, albedo, bvec2(true), vec3(0.5), vec3(0.0), vec3(1.0));
}
