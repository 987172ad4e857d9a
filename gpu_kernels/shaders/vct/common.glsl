// SPDX-License-Identifier: GPL-3.0-or-later
// Voxel cone tracing (Crassin et al. 2011; Freed 2018, §3.4, §4.5.2): the grid, the cone table, one cone step through
// the filtered radiance volumes, and the cosine-weighted hemisphere gather shared by the per-voxel bounce pass
// (vct/bounce.glsl) and the per-pixel trace (vct/trace.glsl). gpu_kernels/vct/ (settings.py, cones.py) documents
// every constant.
//
// Volumes hold optical depth τ and τ-weighted radiance (rgb = τ·S, a = τ), see vct/mipmap.glsl.
// MODE_ANISO: six volumes, one per direction of travel (+x, −x, +y, −y, +z, −z), each holding what a ray
// travelling that way sees (vct/mipmap.glsl). Otherwise one isotropic volume.
#pragma once

#define MAX_CONES 32
#define MAX_STEPS 1024
#define MIN_TRANSMITTANCE 1e-3   // stop a cone when < 0.1% of it is left: the error is below 0.1% of its radiance

uniform vec3 u_grid_origin;      // world position of the grid's min corner
uniform float u_grid_cell;            // voxel edge (m)
uniform ivec3 u_grid_size;       // voxels per axis at level 0 (a multiple of 2^u_max_lod, so levels nest exactly)
uniform float u_max_lod;         // coarsest mip level
uniform int u_cone_count;
uniform vec4 u_cones[MAX_CONES]; // xyz: unit direction in the normal's frame (z = normal); w: weight ∫region cosθ dω
uniform float u_cone_tan[MAX_CONES];   // tan(half-angle)
uniform float u_step;            // step length / sampled voxel size (Freed 2018, listing 4.1, steps by the radius: 0.5)
uniform float u_offset;          // start offset along the geometric normal, in voxels (scaled by ‖n‖₁, see below)
uniform float u_max_distance;    // metres; 0 = until the cone leaves the grid
uniform float u_ao_distance;     // metres; 0 = AO is the sky visibility (transmittance of cones leaving the grid)

uniform sampler3D u_centroid[6]; // vct/inject.glsl: per face, xyz = its surface centroid, w = ±coverage (0: no surface)
#include "vct/arrays.glsl"
VCT_FETCH6(centroid_face, u_centroid)
#if defined(MODE_ANISO)
uniform sampler3D u_volume[6];
uniform sampler3D u_layers;      // vct/mipmap.glsl MODE_LAYERS: rgb = τ_i · (surface coordinate along axis i)
#else
uniform sampler3D u_volume[1];
#endif

const float VCT_PI = 3.14159265358979;

#include "vct/hits.glsl"
#if defined(MODE_RECORD_GATHER)
vec3 g_weights;   // cone_step's axis weights and optical depth at its last sample, for record_step
float g_tau;
#endif

// Premultiplied radiance and opacity of one step of k texels of the sampled level along unit direction d, from
// volumes storing (τ·S, τ) (vct/mipmap.glsl): α' = 1 − e^(−k·τ), the usual step-length correction
// α' = 1 − (1 − α)^k written in optical depth; radiance S = τ·S / τ, the τ-weighted mean of the filtered texels.
// Anisotropic: τ_i of the volume for the sign of d_i is the optical depth of crossing one texel along axis i. A
// planar layer with normal along i is crossed once by a ray at any angle, so its optical depth per unit length
// along d is |d_i|·τ_i; summed over the axes this is exact for axis-aligned layers (Crassin's d² weights would let
// a layer leak at grazing angles). S is the τ-weighted mean of the three volumes.
vec4 cone_step(vec3 uvw, float lod, vec3 d, float k, vec3 start) {
#if defined(MODE_ANISO)
    vec4 sx = d.x >= 0.0 ? textureLod(u_volume[0], uvw, lod) : textureLod(u_volume[1], uvw, lod);
    vec4 sy = d.y >= 0.0 ? textureLod(u_volume[2], uvw, lod) : textureLod(u_volume[3], uvw, lod);
    vec4 sz = d.z >= 0.0 ? textureLod(u_volume[4], uvw, lod) : textureLod(u_volume[5], uvw, lod);
    vec3 w = abs(d);
    float tau = w.x * sx.a + w.y * sy.a + w.z * sz.a;
    if (tau <= 1e-9) return vec4(0.0);
    // A cone meets only surfaces ahead of where it started. Filtering reads texels up to one texel behind the
    // sample, and their radiance for this direction of travel is the side facing away from the cone: a cone
    // passing under a sunlit roof read its lit top (measured: the courtyard's upper walls 2.2× as bright after one
    // bounce as with the roof's top face blacked out). So axis i (its optical depth and its radiance) is skipped
    // where the filtered surface position along i (MODE_LAYERS) lies behind both the sample and the cone's start:
    // a surface the cone never crossed. One it crossed (between start and sample) keeps the back half of its τ
    // hat, so it stops the cone exactly as much as before. Measured: the courtyard's upper walls 2.2× → 1.33× (the
    // rest: the filtered position is a mean, and on coarse levels it mixes the roof with the floor); 8 bounces,
    // Diffuse Indirect rel-L1 against 2048-spp Cycles: courtyard 0.244 → 0.178, Cornell 0.150 → 0.137, the
    // anisotropic white furnace 94.2% → 97.6% of the exact light (a wall beside the cone's start no longer absorbs
    // it through the filter).
    vec4 layer = textureLod(u_layers, uvw, lod);
    vec3 g = uvw * vec3(u_grid_size);
    vec3 tau_axis = vec3(sx.a, sy.a, sz.a);
    vec3 seen = vec3(1.0);
    for (int i = 0; i < 3; ++i) {
        if (tau_axis[i] <= 0.0) continue;
        float c = layer[i] / tau_axis[i];
        if ((c - g[i]) * d[i] < 0.0 && (c - start[i]) * d[i] < 0.0) seen[i] = 0.0;
    }
    w *= seen;
    tau = w.x * sx.a + w.y * sy.a + w.z * sz.a;
    if (tau <= 1e-9) return vec4(0.0);
    vec3 radiance = (w.x * sx.rgb + w.y * sy.rgb + w.z * sz.rgb) / tau;   // gather_replay (vct/bounce.glsl) too
#if defined(MODE_RECORD_GATHER)
    g_weights = w;
    g_tau = tau;
#endif
#else
    vec4 s = textureLod(u_volume[0], uvw, lod);
    float tau = s.a;
    if (tau <= 1e-9) return vec4(0.0);
    vec3 radiance = s.rgb / tau;
#endif
    float alpha = 1.0 - exp(-k * tau);
    return vec4(alpha * radiance, alpha);
}

struct ConeResult {
    vec3 radiance;        // radiance gathered along the cone (premultiplied by what was left of it)
    float transmittance;  // what is left of the cone where it stopped
    bool exited;          // it left the grid (the world shows through the rest)
    float ao;             // transmittance at u_ao_distance, or the sky visibility when that is 0
};

#if defined(MODE_RECORD_GATHER)
// A step of trace_cone that absorbed part of its cone (vct/hits.glsl GatherStep): all a replay needs but the radiance.
void record_step(vec3 uvw, float lod, float alpha, float transmittance, vec3 d) {
    uint i = hit_slot();
    if (i == HIT_FULL) return;
    uint volumes = uint(d.x < 0.0) | (uint(d.y < 0.0) << 1) | (uint(d.z < 0.0) << 2);   // 2a + 1 where d_a < 0
    gather_steps[i] = GatherStep(vec4(uvw, lod), vec4(g_weights, g_tau),
                                 vec4(alpha, transmittance, uintBitsToFloat(uint(g_cone) | (volumes << 5)), 0.0));
}
#endif

// March one cone from surface point p (geometric normal n_geo, unit) along unit d with tan(half-angle) tan_half,
// absorbing it volumetrically: the bounce gathers at voxel faces, the specular cone, and isotropic volumes use this;
// the per-pixel diffuse cones with anisotropic volumes are bundles of sub-rays instead (vct/crossing.glsl).
//
// Self-occlusion (derived, not tuned): trilinear filtering at level l reads texels whose centres lie within one
// texel V = cell·2^l of the sample on every axis, and the texel holding p has its centre at most V/2·‖n‖₁ above p's
// tangent plane, so a sample at height h above that plane reads none of p's own texels iff h ≥ 1.5·V·‖n‖₁. Hence
// the start offset of 1.5 voxels (× ‖n‖₁) along the normal, and the level is capped at
// floor(log2(h / (1.5·‖n‖₁·cell))): grazing cones sample finer levels (more, shorter steps) rather than the surface
// they start from. The level otherwise follows the cone diameter (Freed 2018, listing 4.1: lod = log2(diameter)).
// Known bias (measured): a capped cone reads a footprint narrower than itself, so a bright area at its centre counts
// for the whole cone — a 3 m lit square seen from 3 m above came out 35% too bright, a 0.6 m one 20% too dark.
// Four lateral samples per capped step did not help (+56% on the 3 m square): τ blended across a surface's edge
// overstates its coverage (Jensen), and more samples across the cone meet more edges.
ConeResult trace_cone(vec3 p, vec3 o, vec3 n_geo, vec3 d, float tan_half) {
    float n1 = abs(n_geo.x) + abs(n_geo.y) + abs(n_geo.z);
    float h0 = dot(o - p, n_geo);
    float dh = dot(d, n_geo);
    float ao_limit = u_ao_distance > 0.0 ? u_ao_distance : 3.4e38;
    ConeResult r = ConeResult(vec3(0.0), 1.0, false, 1.0);
    bool ao_set = false;
    float t = 0.0;
    vec3 inv_size = 1.0 / vec3(u_grid_size);
    vec3 g0 = (o - u_grid_origin) / u_grid_cell;   // the cone's start, voxel units
    for (int i = 0; i < MAX_STEPS; ++i) {
        vec3 g = (o + d * t - u_grid_origin) / u_grid_cell;
        if (any(lessThan(g, vec3(0.0))) || any(greaterThan(g, vec3(u_grid_size)))) {
            r.exited = true;
            break;
        }
        if ((u_max_distance > 0.0 && t > u_max_distance)) break;
        if (!ao_set && t >= ao_limit) {
            r.ao = r.transmittance;
            ao_set = true;
        }
        float lod = log2(max(2.0 * t * tan_half, u_grid_cell) / u_grid_cell);
        float h = h0 + t * dh;
        float cap = floor(log2(max(h / (1.5 * n1 * u_grid_cell), 1.0)));
        lod = min(min(lod, cap), u_max_lod);
        vec4 s = cone_step(g * inv_size, lod, d, u_step, g0);
#if defined(MODE_RECORD_GATHER)
        if (s.a > 0.0) record_step(g * inv_size, lod, s.a, r.transmittance, d);
#endif
        r.radiance += r.transmittance * s.rgb;
        r.transmittance *= 1.0 - s.a;
        if (r.transmittance < MIN_TRANSMITTANCE) break;
        t += u_step * u_grid_cell * exp2(lod);
    }
    if (!ao_set) r.ao = u_ao_distance > 0.0 ? r.transmittance : (r.exited ? r.transmittance : 0.0);
    return r;
}

// Orthonormal basis around unit n (Duff et al. 2017, "Building an orthonormal basis, revisited").
void onb(vec3 n, out vec3 t1, out vec3 t2) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    t1 = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    t2 = vec3(b, s + n.y * n.y * a, -n.y);
}

// The cone origin: p moved u_offset voxels (× ‖n‖₁) along the normal (see trace_cone), then out of any voxel that
// holds another surface. A point within a voxel of a wall it stands beside (a floor pixel at an edge, a corner)
// would otherwise start inside that wall's voxel, and a ray leaving it away from the wall would meet the voxel's
// far face — the wall's back — as if it still had to cross the wall (the white furnace lost up to 40% of its light
// next to the box's edges). So for each axis, the voxel holding o and its two neighbours along it are checked for a
// surface across that axis lying between p's side and o (its position: the centroid of its faces, vct/inject.glsl),
// and o moves along the axis, to p's side, to at least the centre of the voxel next to it: there the trilinear
// support of the first sample no longer reaches the wall's voxel. Measured (anisotropic white furnace, 32³): 92.7% →
// 94.8% of the exact value overall, 60% → 87% within 2 cm of the box's edges.
vec3 cone_origin(vec3 p, vec3 n_geo) {
    float n1 = abs(n_geo.x) + abs(n_geo.y) + abs(n_geo.z);
    vec3 o = p + n_geo * (u_offset * n1 * u_grid_cell);
    ivec3 v0 = ivec3(floor((o - u_grid_origin) / u_grid_cell));
    for (int b = 0; b < 3; ++b) {
        for (int k = -1; k <= 1; ++k) {   // the voxel holding o and its two neighbours along b
            ivec3 v = v0;
            v[b] += k;
            if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, u_grid_size))) continue;
            vec4 cp = centroid_face(2 * b, v, 0), cm = centroid_face(2 * b + 1, v, 0);
            if (cp.w == 0.0 && cm.w == 0.0) continue;
            float s = cp.w != 0.0 && cm.w != 0.0 ? 0.5 * (cp[b] + cm[b]) : (cp.w != 0.0 ? cp[b] : cm[b]);
            float side = p[b] - s;
            if (side == 0.0 || (k < 0 && side < 0.0) || (k > 0 && side > 0.0)) continue;   // a surface beyond o
            float target = u_grid_origin[b] + (float(v[b]) + (side > 0.0 ? 1.5 : -0.5)) * u_grid_cell;
            o[b] = side > 0.0 ? max(o[b], target) : min(o[b], target);
        }
    }
    return o;
}

#if defined(MODE_CROSSING)
#include "vct/crossing.glsl"
#endif

// Irradiance E at p over the hemisphere of n (rgb), and the cosine-weighted AO / sky visibility (a, in [0, 1]):
// E = Σ_k w_k·L_k, with Σ_k w_k = π (vct/cones.cone_table). The world a cone reaches is not added: it is a light
// (common/lights.py: the sky light), its direct light shadowed by the real triangles and its bounce injected into the
// voxels like any light's, since a voxel's fuzzy opacity lets the sky through walls thinner than a voxel.
// rot = (cos φ, sin φ): the cone set turned by φ around the normal (vct/temporal.py jitters φ from frame to frame;
// the weights are unchanged, since rotating the regions about the normal keeps their cosine integrals).
vec4 gather_irradiance(vec3 p, vec3 n, vec3 n_geo, vec2 rot) {
    vec3 o = cone_origin(p, n_geo);
    vec3 t1, t2;
    onb(n, t1, t2);
    vec3 e = vec3(0.0);
    float ao = 0.0;
    for (int k = 0; k < u_cone_count; ++k) {
        vec4 c = u_cones[k];
        vec2 xy = vec2(rot.x * c.x - rot.y * c.y, rot.y * c.x + rot.x * c.y);
        vec3 d = normalize(t1 * xy.x + t2 * xy.y + n * c.z);
#if defined(MODE_RECORD) || defined(MODE_RECORD_GATHER)
        g_cone = k;
#endif
#if defined(MODE_CROSSING)
        ConeResult r = trace_cone_crossing(o, d, u_cone_tan[k]);
#else
        ConeResult r = trace_cone(p, o, n_geo, d, u_cone_tan[k]);
#endif
        e += c.w * r.radiance;
        ao += c.w * r.ao;
    }
    return vec4(e, ao / VCT_PI);
}
