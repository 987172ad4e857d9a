// SPDX-License-Identifier: GPL-3.0-or-later
// Per-pixel diffuse cones as bundles of sub-rays that meet surfaces where they cross them (MODE_CROSSING, anisotropic
// volumes only; included by vct/common.glsl). vct/trace.glsl uses it; the bounce gathers keep trace_cone.
//
// Why not the volumetric march (trace_cone, cone_step): it spreads a surface's optical depth over the trilinear hat
// of its texels and absorbs a cone wherever that hat reaches, so
//   - a cone skimming a floor (its axis level with it) never met it: the floor's τ counts along the axis direction
//     only, |d_z|·τ_z = 0 — the courtyard's lower walls, which see the sunlit floor patch at grazing angles, got 2–7%
//     of their light after one bounce;
//   - a cone passing under a sunlit roof read its lit top through the hat, and a cone's own level had to be capped
//     by its height above its start surface (a footprint narrower than the cone over-weights its axis: upper walls
//     1.4–2.2× too bright).
// Here each cone is `u_subrays` rays: its axis and u_subrays − 1 rays around it at u_subray_radius·tan(half-angle)
// (the centroid radius of the outer ring when the cone's disc is cut into equal areas, vct.subray_radius), each
// with its own transmittance T_j and equal weight. The samples are shared: at every step the three texels along
// each axis around the sample are read at the cone's level, and the layer volume (vct/mipmap.glsl MODE_LAYERS) says
// where, along that axis, each texel's surfaces lie (the τ-weighted mean position), in the columns through the
// axis's positions at the step's start and end. A sub-ray meets those surfaces iff it is behind that position at
// the start and not at the end; then it gathers α·S of what is left of it (T_j − α), with α and S read where it
// crosses, one level finer than the cone (about a sub-ray's own width; the cone's level blurred a lit patch over its
// neighbours' sub-rays: a 3 × 2.5 m lit patch seen from a plate 3 m above came out 1.23× the exact integral read at
// the cone's level, 1.01× one level finer), over both finer texels of the crossed one in the sub-ray's own column.
// Surfaces that are not aligned with the axes (a room turned 30°, a sphere) are why the crossing is tested this way.
// Such a surface lies at another depth in each column of texels, so a depth read once per step jumped between steps
// and a sub-ray could step over it. Its staircase of voxels also covers complementary parts of a column (two
// neighbours covering 0.4 and 0.6 of it), so coverages of one step add up (Carpenter 1984, "The A-buffer": the
// coverage of adjacent fragments of one surface) rather than multiply like independent layers, which let 15% through
// a wall turned 30° (the mean transmittance along x through its voxels). And the finer read follows the surface into
// whichever finer texel holds it in the sub-ray's column, not the one holding the texel's mean depth. Measured, the
// share of the closed white furnace's light that escaped the per-pixel cones (64³, one bounce): 2.0% → 2.0% as
// built, 29% → 9% turned 30° about z (its Diffuse Indirect 0.67 → 0.86 of the exact value); inside a closed sphere
// lit from its centre the first bounce is 0.54 → 0.89 of the exact value (tests/gpu/test_vct_off_grid.py).
// Consequences: a surface behind a sub-ray's start is never crossed, so cones need no level cap (the level follows
// the diameter, Freed 2018, listing 4.1); a sub-ray level with a floor never meets it, one tilted down meets it where
// it actually gets there; a sub-ray is absorbed only by surfaces it passes through, so one leaving the grid sees the
// world with what is left of it. Measured against exact integrals and Cycles: see vct/settings.py
// (VctSettings.subrays).
#pragma once
#if defined(MODE_CROSSING)

#if !defined(SUBRAYS)
#define SUBRAYS 7                 // the axis and SUBRAYS − 1 rays around it (a define: loops of constant length
#endif                            // keep the per-sub-ray arrays in registers)
uniform float u_subray_radius;    // their distance from the axis, in units of tan(half-angle)
// Sub-rays find surfaces by crossing, not by sampling them, so a step of one texel misses nothing that the three
// texels read around each sample cover (see `limit` below); measured against half a texel (19 cones): Cornell / spot
// room / courtyard Diffuse Indirect 0.074 / 0.058 / 0.070 vs 0.079 / 0.056 / 0.070, at 1.6× the time for the latter.
#define STEP_TEXELS 1.0
#if SUBRAYS > 10
#error "cross_axis keeps 3 bits per sub-ray in one uint"
#endif

// Where along axis a the surfaces of texel `idx` (of size `texel`, level `lod`) lie, in the column through uvw:
// the τ-weighted mean position of the layer volume (vct/mipmap.glsl MODE_LAYERS), or −1 where the texel is empty.
// `a` must be the same in every lane (a constant: reach_axis): it indexes u_volume.
float surface_along(vec3 uvw, int a, float idx, float texel, float lod) {
    vec3 q = uvw;
    q[a] = (idx + 0.5) * texel / float(u_grid_size[a]);
    float layer = textureLod(u_layers, q, lod)[a];   // τ_a · position: 0 where the texel is empty
    if (layer <= 0.0) return -1.0;
    // τ_a is the same in the volumes for both directions along a (vct/mipmap.glsl MODE_LAYERS).
    float tau = textureLod(u_volume[2 * a], q, lod).a;
    return tau > 0.0 ? layer / tau : -1.0;
}

// Where along axis a (a constant at each call: it indexes u_volume) the surfaces of the texels in `bits` lie (bit k:
// texel mid − 1 + k around the step's sample g), in the columns through the step's start and end (wa, wb, index
// 3a + k; −1: none there, or the other end's where only one has one).
void reach_axis(const int a, uint bits, vec3 g, float texel, float lod, vec3 uvw_a, vec3 uvw_b, inout float wa[9],
                inout float wb[9], inout bool any_surface) {
    while (bits != 0u) {
        int k = findLSB(bits);
        bits &= bits - 1u;
        int n = 3 * a + k;
        float idx = floor(g[a] / texel) - 1.0 + float(k);
        wa[n] = surface_along(uvw_a, a, idx, texel, lod);
        wb[n] = surface_along(uvw_b, a, idx, texel, lod);
        if (wa[n] < 0.0) wa[n] = wb[n];
        if (wb[n] < 0.0) wb[n] = wa[n];
        any_surface = any_surface || wa[n] >= 0.0;
    }
}

// The surfaces across axis a (a constant at each call: it indexes u_volume) that the sub-rays cross in this step
// (bit 3j + k: sub-ray j through texel k's surfaces, from its start ga[j] to its end gb[j]), in that order: each
// gathers α·S of what is left of it. Called for the axes in order 0, 1, 2, so each sub-ray meets its crossings in
// the order the search found them (α = min(1 − e^−τ, T_j) depends on it); only the sum over sub-rays is taken axis
// by axis.
void cross_axis(const int a, uint bits, vec3 ga[SUBRAYS], vec3 gb[SUBRAYS], float wa[9], float wb[9], float texel,
                float lod, vec3 inv_size, inout float T[SUBRAYS], inout vec3 radiance) {
    const float inv_ns = 1.0 / float(SUBRAYS);
    float hit_lod = max(lod - 1.0, 0.0);
    float hit_texel = exp2(hit_lod);
    while (bits != 0u) {
        int bit = findLSB(bits);
        bits &= bits - 1u;
        int j = bit / 3, n = 3 * a + bit - 3 * (bit / 3);
        vec3 m = gb[j] - ga[j];
        float fa = (wa[n] - ga[j][a]) * sign(m[a]), fb = (wb[n] - gb[j][a]) * sign(m[a]);
        vec3 hit = ga[j] + m * (fa / (fa - fb));
        // What the sub-ray meets is read one level finer than the cone, in its own column, over the whole depth of
        // the crossed texel (its two finer texels along a, front first): a tilted surface lies in either of them
        // there, wherever the texel's mean depth put the crossing.
        float idx = floor(hit[a] / texel);
        int parts = lod > 0.0 ? 2 : 1;
        for (int h = 0; h < parts; ++h) {
            float fine = parts == 1 ? idx : 2.0 * idx + float(m[a] > 0.0 ? h : 1 - h);
            vec3 q = hit;
            q[a] = (fine + 0.5) * hit_texel;
            q *= inv_size;
            vec4 s = m[a] > 0.0 ? textureLod(u_volume[2 * a], q, hit_lod)
                                : textureLod(u_volume[2 * a + 1], q, hit_lod);
            if (s.a <= 0.0) continue;
            float alpha = min(1.0 - exp(-s.a), T[j]);
            radiance += inv_ns * alpha * s.rgb / s.a;   // vct/hits.glsl replays this term
#if defined(MODE_RECORD)
            record_hit(q, hit_lod, m[a] > 0.0 ? 2 * a : 2 * a + 1, alpha);
#endif
            T[j] -= alpha;
        }
    }
}

ConeResult trace_cone_crossing(vec3 o, vec3 d, float tan_half) {
    float ao_limit = u_ao_distance > 0.0 ? u_ao_distance : 3.4e38;
    ConeResult r = ConeResult(vec3(0.0), 1.0, false, 1.0);
    bool ao_set = false;
    vec3 size = vec3(u_grid_size);
    vec3 inv_size = 1.0 / size;
    vec3 g0 = (o - u_grid_origin) / u_grid_cell;   // the cone's start, voxel units
    const int ns = SUBRAYS;
    const float inv_ns = 1.0 / float(SUBRAYS);
    vec3 dev[SUBRAYS];   // sub-ray direction − axis direction
    float T[SUBRAYS];
    vec3 t1, t2;
    onb(d, t1, t2);
    for (int j = 0; j < ns; ++j) {
        float phi = 6.283185307 * float(j - 1) / float(max(ns - 1, 1));
        dev[j] = j == 0 ? vec3(0.0)
                        : normalize(d + u_subray_radius * tan_half * (cos(phi) * t1 + sin(phi) * t2)) - d;
        T[j] = 1.0;
    }
    float escaped = 0.0;                 // Σ T_j of the sub-rays that left the grid
    float t = 0.0, seg_start = 0.0;      // voxel units along the axis; step i covers [seg_start, t + step/2]
    for (int i = 0; i < MAX_STEPS; ++i) {
        if (u_max_distance > 0.0 && seg_start * u_grid_cell > u_max_distance) break;
        float lod = min(floor(log2(max(2.0 * t * tan_half, 1.0))), u_max_lod);
        float texel = exp2(lod);
        float seg_end = t + 0.5 * STEP_TEXELS * texel;
        // The three texels read along each axis reach at least one texel either side of the sample. A sub-ray lies
        // ≤ 0.74·tan·t < 0.74 texel off the axis (texel > t·tan below the coarsest level; clamped to 1.2 texels
        // beyond it) and a step moves it ≤ 0.5 texel, so only a crossing in the outermost quarter texel of its reach
        // can go unread: the closed white furnace keeps 97.9% of its light (97.6% with the volumetric march).
        float limit = 1.2 * texel;
        vec3 ga[SUBRAYS], gb[SUBRAYS];
        vec3 lo = vec3(3.4e38), hi = vec3(-3.4e38);
        float alive = 0.0;
        for (int j = 0; j < ns; ++j) {
            ga[j] = g0 + d * seg_start + clamp(dev[j] * seg_start, -limit, limit);
            gb[j] = g0 + d * seg_end + clamp(dev[j] * seg_end, -limit, limit);
            if (T[j] <= 0.0) continue;
            if (any(lessThan(ga[j], vec3(0.0))) || any(greaterThan(ga[j], size))) {   // it sees the world
                escaped += T[j];
                T[j] = 0.0;
                continue;
            }
            alive += T[j];
            lo = min(lo, min(ga[j], gb[j]));
            hi = max(hi, max(ga[j], gb[j]));
        }
        if (!ao_set && seg_start * u_grid_cell >= ao_limit) {
            r.ao = (alive + escaped) * inv_ns;
            ao_set = true;
        }
        if (alive * inv_ns < MIN_TRANSMITTANCE) break;
        vec3 g = clamp(g0 + d * t, vec3(0.0), size);
        vec3 uvw_a = clamp(g0 + d * seg_start, vec3(0.0), size) * inv_size;
        vec3 uvw_b = clamp(g0 + d * seg_end, vec3(0.0), size) * inv_size;
        // Per axis a, the texels mid − 1 … mid + 1 along a (mid holds the sample) that some sub-ray's path reaches,
        // and where along a their surfaces lie, read in the columns through the axis's position at the step's start
        // (wa) and end (wb): a tilted surface lies at another depth in each column.
        // Voxel units; −1: no surface (surfaces lie at ≥ 1: the grid has an empty margin voxel).
        float wa[9], wb[9];
        bool any_surface = false;
        uint reached = 0u;   // the texels some sub-ray's path reaches, read below (as the crossings: see there)
        for (int a = 0; a < 3; ++a) {
            float mid = floor(g[a] / texel);
            for (int k = 0; k < 3; ++k) {
                float idx = mid - 1.0 + float(k);
                int n = 3 * a + k;
                wa[n] = -1.0;
                wb[n] = -1.0;
                // Outside the grid there is nothing (no clamped copies of the border texels).
                if (idx < 0.0 || idx >= size[a] / texel || (idx + 1.0) * texel < lo[a] || idx * texel > hi[a])
                    continue;
                reached |= 1u << n;
            }
        }
        reach_axis(0, reached & 7u, g, texel, lod, uvw_a, uvw_b, wa, wb, any_surface);
        reach_axis(1, (reached >> 3) & 7u, g, texel, lod, uvw_a, uvw_b, wa, wb, any_surface);
        reach_axis(2, reached >> 6, g, texel, lod, uvw_a, uvw_b, wa, wb, any_surface);
        // The crossings are found first and read after (cross_axis): per axis a, one bit per sub-ray j and texel k
        // (bit 3j + k). llvmpipe runs a loop's body for every SIMD lane whenever one lane needs it, so reading while
        // searching read two textures for each of the SUBRAYS × 9 candidates at every step (as vct/arrays.glsl's
        // switches); only crossings are read now.
        uvec3 crossed = uvec3(0u);
        for (int j = 0; j < ns && any_surface; ++j) {   // in empty space there is nothing to cross
            if (T[j] < MIN_TRANSMITTANCE) continue;
            vec3 m = gb[j] - ga[j];
            for (int a = 0; a < 3; ++a) {
                if (m[a] == 0.0) continue;
                for (int k = 0; k < 3; ++k) {
                    int n = 3 * a + k;
                    if (wa[n] < 0.0) continue;
                    // Crossed in this step: ahead of the sub-ray at the start, not ahead at the end (in the direction
                    // of travel). With the surface's depth read at both ends, a step's end and the next one's start
                    // agree, so a tilted surface is met once, not stepped over.
                    float fa = (wa[n] - ga[j][a]) * sign(m[a]), fb = (wb[n] - gb[j][a]) * sign(m[a]);
                    if (fa <= 0.0 || fb > 0.0) continue;
                    vec3 hit = ga[j] + m * (fa / (fa - fb));
                    if (any(lessThan(hit, vec3(0.0))) || any(greaterThan(hit, size))) continue;   // beyond the grid
                    crossed[a] |= 1u << (3 * j + k);
                }
            }
        }
        cross_axis(0, crossed.x, ga, gb, wa, wb, texel, lod, inv_size, T, r.radiance);
        cross_axis(1, crossed.y, ga, gb, wa, wb, texel, lod, inv_size, T, r.radiance);
        cross_axis(2, crossed.z, ga, gb, wa, wb, texel, lod, inv_size, T, r.radiance);
        seg_start = seg_end;
        t += STEP_TEXELS * texel;
    }
    float left = 0.0;
    for (int j = 0; j < ns; ++j) left += max(T[j], 0.0);
    r.exited = escaped > 0.0;
    r.transmittance = escaped * inv_ns;   // the part that reaches the world
    if (!ao_set) r.ao = u_ao_distance > 0.0 ? (left + escaped) * inv_ns : escaped * inv_ns;
    return r;
}
#endif
