// SPDX-License-Identifier: GPL-3.0-or-later
// The sky light's visible shares at a pixel (direct/light.glsl MODE_SKY, direct/sky.py), from one shadow test per
// direction d_k of its K (direct/eval.glsl sky_direction): x of the cosine weight (irradiance), y (when `lobe_seen`)
// of the glossy lobe's (direct/ggx.glsl sky_lobe_weight), z the penumbra's half-width. Each direction stands for its
// cell of the sphere (4π/K); a cell that an opening's edge crosses is tested over its whole cone (sky_soften), so
// the shares vary smoothly across a room lit through a window instead of stepping once per direction. Needs
// light.glsl's G-buffer inputs.
#pragma once

// The lobe's α² is widened by SKY_LOBE_SPREAD / K so that a mirror still averages its few nearest directions rather
// than one.
#define SKY_LOBE_SPREAD 2.0

struct SkySums {
    vec4 weights;   // x, y: Σ w over the directions counted (cosine, lobe); z, w: Σ w · seen
    vec2 penumbra;  // over the blocked directions: x Σ w.x / gap (gap in metres), y Σ w.x
};

// Direction d's weights: the cosine, and the glossy lobe's where `lobe_seen`.
vec2 sky_direction_weights(vec3 d, vec3 n, GlossyLobe lobe, GlossyFresnel fresnel, float a2, vec3 v,
                           bool lobe_seen) {
    return vec2(max(dot(n, d), 0.0), lobe_seen ? sky_lobe_weight(lobe, fresnel, a2, n, v, d) : 0.0);
}

// Direction k's weights; false where it lies below the surface's horizon or weighs nothing.
bool sky_weights(GpuLight L, int k, vec3 n, vec3 geo_n, GlossyLobe lobe, GlossyFresnel fresnel, float a2, vec3 v,
                 bool lobe_seen, out vec3 d, out vec2 w) {
    w = vec2(0.0);
    if (!sky_direction(L, k, geo_n, d)) return false;
    w = sky_direction_weights(d, n, lobe, fresnel, a2, v, lobe_seen);
    return max(w.x, w.y) > 0.0;
}

float sky_lobe_a2(GlossyLobe lobe, int samples) {
    return lobe.alpha * lobe.alpha + SKY_LOBE_SPREAD / float(samples);
}

#if defined(MODE_SKY)
// The cells an edge crosses. A hard test per direction makes the share step by a whole cell's weight wherever an
// opening's edge passes a direction: through a window a few directions of the hundreds reach the sky, so a room's
// walls showed ±10–20% blotches that no filter over the image removed without blurring the light's real gradients.
// Where a counted direction and one of its neighbours differ (seen / blocked), its cell is tested over
// its cone instead: SKY_TAPS rays spread over a disc of the cell's radius at the blockers' distance g, each read
// from the direction's own map (the cone's ray at distance g from p crosses the map there) and weighted by its own
// direction — as percentage-closer soft shadows size a filter by the blocker's distance (Fernando 2005,
// "Percentage-closer soft shadows"). A tap's parallel ray strays from the cone's ray near p, so a blocker counts
// only beyond the nearest SKY_SLAB of g and in front of the receiver's own plane (which never shadows itself).
// SKY_WORDS words of bits per pixel: a sky of more directions keeps hard tests.
#define SKY_WORDS 24
#define SKY_TAPS 12
#define SKY_SLAB 0.25
#define GOLDEN_ANGLE 2.39996323
// Per direction its nearest six and every direction that has it among its nearest six, SKY_NEIGHBOURS in all
// (direct/sky.py neighbours: the relation made mutual, so the edge cells are the same whichever side marks them;
// padded with the direction itself).
layout(std430, binding = 14) readonly buffer SkyNeighbours { int sky_neighbours[]; };  // K × SKY_NEIGHBOURS

// Per direction, one bit each: counted, seen, and on an edge (this invocation's own: globals, not arguments, so
// that no call copies them).
uint sky_counted[SKY_WORDS];
uint sky_seen[SKY_WORDS];
uint sky_edge[SKY_WORDS];

bool sky_bit(uint word, int k) {
    return (word & (1u << uint(k & 31))) != 0u;
}

// The edge cells: counted directions with a counted neighbour whose test differs. Found from whichever of the seen
// and the blocked directions are fewer (a window: its few seen ones; the open sky: its few blocked ones), each
// marking itself and its differing neighbours. The words are read whole and their set bits visited (llvmpipe runs
// an array read at a varying index as a gather per lane).
void sky_mark_edges(int samples, bool from_seen) {
    for (int i = 0; i < SKY_WORDS; ++i) sky_edge[i] = 0u;
    for (int word = 0; 32 * word < samples; ++word) {
        uint few = from_seen ? sky_seen[word] : sky_counted[word] & ~sky_seen[word];
        for (; few != 0u; few &= few - 1u) {
            int k = 32 * word + findLSB(few);
            for (int j = 0; j < SKY_NEIGHBOURS; ++j) {
                int m = sky_neighbours[SKY_NEIGHBOURS * k + j];
                if (!sky_bit(sky_counted[m >> 5], m) || sky_bit(sky_seen[m >> 5], m) == from_seen) continue;
                sky_edge[word] |= 1u << uint(k & 31);
                sky_edge[m >> 5] |= 1u << uint(m & 31);
            }
        }
    }
}

// Cell k's cone at p: (Σ w, Σ w · seen) / SKY_TAPS over its taps (a tap below the horizon counts for nothing);
// false where p's own point lies outside the direction's map (its hard test stands).
bool sky_cone_taps(int view, vec3 p, vec3 n, vec3 geo_n, vec3 d, float g, int k, GlossyLobe lobe,
                   GlossyFresnel fresnel, float a2, vec3 v, bool lobe_seen, float cell, out vec4 sum) {
    ShadowView sv = shadow_views[view];
    vec3 q = biased_point(sv, p, geo_n, d, 0.0);
    vec2 uv0;
    float depth;
    sum = vec4(0.0);
    if (!view_project(sv, q, uv0, depth) || !in_tile(sv, uv0)) return false;
    vec2 slope = receiver_slope(sv, q, geo_n, uv0, depth);
    float beyond = depth - SKY_SLAB * g / ortho_depth_scale(view);
    float radius = g * tan(cell);
    vec3 t1 = normalize(cross(d, abs(d.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
    vec3 t2 = cross(d, t1);
    vec2 lo = sv.tile.xy + 0.5 * u_atlas_texel, hi = sv.tile.xy + sv.tile.zw - 0.5 * u_atlas_texel;
    for (int i = 0; i < SKY_TAPS; ++i) {
        float angle = GOLDEN_ANGLE * float(i + 7 * k);   // a Vogel disc, turned per direction
        vec3 o = radius * sqrt((float(i) + 0.5) / float(SKY_TAPS)) * (cos(angle) * t1 + sin(angle) * t2);
        vec3 di = normalize(g * d + o);
        if (dot(geo_n, di) < SKY_MIN_COS) continue;
        vec2 w = sky_direction_weights(di, n, lobe, fresnel, a2, v, lobe_seen);
        vec4 clip = sv.view_projection * vec4(q + o, 1.0);
        vec2 uv = sv.tile.xy + (clip.xy * 0.5 + 0.5) * sv.tile.zw;
        float seen = 1.0;   // outside the map: nothing blocks it
        if (in_tile(sv, uv))
            seen = texture(u_shadow_atlas, vec3(clamp(uv, lo, hi), min(beyond, depth + dot(slope, uv - uv0))));
        sum += vec4(w, w * seen);
    }
    sum /= float(SKY_TAPS);
    return true;
}

// How far (m) in front of p the nearest texel of direction view's test lies; 0 where none does.
float sky_gap(int view, vec3 p, vec3 geo_n) {
    float gap;
    view_test(view, p, geo_n, shadow_views[view].emitter.xyz, 0.0, gap);
    return max(gap, 0.0) * ortho_depth_scale(view);
}

// The edge cells' hard tests in `s` replaced by their cones: the blocked ones first, each at its own blocker's
// distance, then the seen ones at the mean of those (a seen direction has no blocker of its own; the blocked edge
// cells' blockers are the opening's frame).
void sky_soften(inout SkySums s, GpuLight L, vec3 p, vec3 n, vec3 geo_n, GlossyLobe lobe,
                GlossyFresnel fresnel, float a2, vec3 v, bool lobe_seen, bool from_seen) {
    int samples = int(L.params.z), first = int(L.params.y);
    float cell = sky_cell_radius(samples);
    sky_mark_edges(samples, from_seen);
    float gaps = 0.0, blocked = 0.0;
    for (int pass = 0; pass < 2; ++pass)
    for (int word = 0; 32 * word < samples; ++word)
        for (uint cells = sky_edge[word] & (pass == 1 ? sky_seen[word] : ~sky_seen[word]); cells != 0u;
             cells &= cells - 1u) {
            int k = 32 * word + findLSB(cells);
            float g = blocked > 0.0 ? gaps / blocked : 0.0;
            if (pass == 0) {
                g = sky_gap(first + k, p, geo_n);
                gaps += g;
                blocked += 1.0;
            }
            if (g <= 0.0) continue;
            vec3 d;
            vec2 w;
            sky_weights(L, k, n, geo_n, lobe, fresnel, a2, v, lobe_seen, d, w);
            vec4 taps;
            if (sky_cone_taps(first + k, p, n, geo_n, d, g, k, lobe, fresnel, a2, v, lobe_seen, cell, taps))
                s.weights += taps - vec4(w, pass == 1 ? w : vec2(0.0));
        }
}
#endif

// The sums of every counted direction's test, and for a pixel (MODE_SKY) the edge cells' cones.
SkySums sky_sums(GpuLight L, vec3 p, vec3 n, vec3 geo_n, GlossyLobe lobe, vec3 v, bool lobe_seen) {
    SkySums s = SkySums(vec4(0.0), vec2(0.0));
    int samples = int(L.params.z), first = int(L.params.y);
    float a2 = sky_lobe_a2(lobe, max(samples, 1));
    GlossyFresnel fresnel = glossy_fresnel_rows(u_material_lut, lobe.material, lobe.mu, lobe.base);
#if defined(MODE_SKY)
    int counted_count = 0, seen_count = 0;
    uint counted_word = 0u, seen_word = 0u;   // stored whole every 32 directions
#endif
    for (int k = 0; k < samples; ++k) {
        vec3 d;
        vec2 w;
        bool counted = sky_weights(L, k, n, geo_n, lobe, fresnel, a2, v, lobe_seen, d, w);
        float seen = 0.0;
        if (counted) {
            s.weights.xy += w;
            float gap;
            seen = view_test(first + k, p, geo_n, d, 0.0, gap);
            s.weights.zw += w * seen;
            if (gap > 0.0 && w.x > 0.0) s.penumbra += vec2(w.x / (gap * ortho_depth_scale(first + k)), w.x);
        }
#if defined(MODE_SKY)
        uint bit = 1u << uint(k & 31);
        if (counted) {
            counted_word |= bit;
            counted_count += 1;
        }
        if (counted && seen > 0.5) {
            seen_word |= bit;
            seen_count += 1;
        }
        if (((k & 31) == 31 || k + 1 == samples) && k < 32 * SKY_WORDS) {
            sky_counted[k >> 5] = counted_word;
            sky_seen[k >> 5] = seen_word;
            counted_word = seen_word = 0u;
        }
#endif
    }
#if defined(MODE_SKY)
    if (samples <= 32 * SKY_WORDS)
        sky_soften(s, L, p, n, geo_n, lobe, fresnel, a2, v, lobe_seen, 2 * seen_count < counted_count);
#endif
    return s;
}

// (share of the cosine weight, of the lobe's, the penumbra's half-width in metres). The penumbra: a direction's cone
// (half-width √(4π/K)/2) at the blockers' distance, the width over which the diffuse share is still averaged on the
// image (direct/sky_filter.glsl); their harmonic mean, so that a receiver beside a wall (many blockers near) keeps
// the contact shadow the wall casts rather than the far blockers' wide fade.
vec3 sky_result(SkySums s, int samples) {
    if (samples == 0) return vec3(1.0, 1.0, 0.0);
    return vec3(s.weights.x > 0.0 ? min(s.weights.z / s.weights.x, 1.0) : 0.0,
                s.weights.y > 0.0 ? min(s.weights.w / s.weights.y, 1.0) : 0.0,
                s.penumbra.x > 0.0 ? 0.5 * sqrt(4.0 * PI / float(samples)) * s.penumbra.y / s.penumbra.x : 0.0);
}

#if defined(MODE_SKY)
// After an object's move (direct/sky.py SkyUpdate): per direction k, the box of the texels its redraw changed
// (x0, y0, x1, y1 in atlas texels; empty where it changed none), and per 8 × 8 block of pixels (a work group) which
// directions' boxes its points can read (direct/sky_tiles.glsl: one bit per direction, u_sky_words words a block).
layout(std430, binding = 11) readonly buffer SkyRedrawn { ivec4 sky_redrawn[]; };
layout(std430, binding = 13) readonly buffer SkyTiles { uint sky_tile_bits[]; };
uniform int u_tiles_x;
uniform int u_sky_words;

// Whether p's tests (the four texels around it, and its cones' taps up to sky_reach texels beyond them) can read a
// texel that the move redrew: if not, its shares of one update ago stand.
bool sky_reads_redrawn(GpuLight L, vec3 p, vec3 geo_n) {
    int first_word = (int(gl_WorkGroupID.y) * u_tiles_x + int(gl_WorkGroupID.x)) * u_sky_words;
    int samples = int(L.params.z);
    for (int word = 0; word < u_sky_words; ++word)
    for (uint bits = sky_tile_bits[first_word + word]; bits != 0u; bits &= bits - 1u) {
        int k = 32 * word + findLSB(bits);
        int view = int(L.params.y) + k;
        ShadowView sv = shadow_views[view];
        vec2 atlas_uv;
        float depth;
        if (!view_uv_depth_biased(sv, p, geo_n, sv.emitter.xyz, 0.0, atlas_uv, depth)) continue;
        vec2 t = gather_point(sv, atlas_uv) / u_atlas_texel - 0.5;
        float reach = sky_reach(view, samples) + 1.0;
        ivec4 r = sky_redrawn[k];
        if (t.x + reach >= float(r.x) && t.x - reach < float(r.z) && t.y + reach >= float(r.y)
            && t.y - reach < float(r.w)) return true;
    }
    return false;
}
#endif

// The shares of sky light L at p (sky_result), every direction tested.
vec2 sky_shares(GpuLight L, vec3 p, vec3 n, vec3 geo_n, GlossyLobe lobe, vec3 v, bool lobe_seen,
                out float penumbra) {
    vec3 r = sky_result(sky_sums(L, p, n, geo_n, lobe, v, lobe_seen), int(L.params.z));
    penumbra = r.z;
    return r.xy;
}
