// SPDX-License-Identifier: GPL-3.0-or-later
// The sky light's visible shares at a pixel (direct/light.glsl MODE_SKY, direct/sky.py), from one shadow test per
// direction d_k of its K (direct/eval.glsl sky_direction): x of the cosine weight (irradiance), y (when `lobe_seen`)
// of the glossy lobe's (direct/ggx.glsl sky_lobe_weight), z the penumbra's half-width. They are kept as sums over the
// directions (SkySums), so that after an object's move a pixel takes out and adds back only the tests whose texels
// the move redrew (sky_sums_update) instead of testing every direction again. Needs light.glsl's G-buffer inputs.
#pragma once

// The lobe's α² is widened by SKY_LOBE_SPREAD / K so that a mirror still averages its few nearest directions rather
// than one.
#define SKY_LOBE_SPREAD 2.0

struct SkySums {
    vec4 weights;   // x, y: Σ w over the directions counted (cosine, lobe); z, w: Σ w · seen
    vec2 penumbra;  // over the blocked directions: x Σ w.x / gap (gap in metres), y Σ w.x
};

// Direction k's weights (cosine; the glossy lobe's where `lobe_seen`); false where it lies below the surface's
// horizon or weighs nothing.
bool sky_weights(GpuLight L, int k, vec3 n, vec3 geo_n, GlossyLobe lobe, GlossyFresnel fresnel, float a2, vec3 v,
                 bool lobe_seen, out vec3 d, out vec2 w) {
    w = vec2(0.0);
    if (!sky_direction(L, k, geo_n, d)) return false;
    w = vec2(max(dot(n, d), 0.0), lobe_seen ? sky_lobe_weight(lobe, fresnel, a2, n, v, d) : 0.0);
    return max(w.x, w.y) > 0.0;
}

// A test of view `view` (seen: 1 or 0; gap: how far in front of p its nearest texel lies, in stored depth) added to
// the sums (sign 1) or taken out of them (sign −1).
void sky_count(inout SkySums s, int view, vec2 w, float seen, float gap, float sign) {
    s.weights.zw += sign * (w * seen);
    if (gap > 0.0 && w.x > 0.0) s.penumbra += sign * vec2(w.x / (gap * ortho_depth_scale(view)), w.x);
}

float sky_lobe_a2(GlossyLobe lobe, int samples) {
    return lobe.alpha * lobe.alpha + SKY_LOBE_SPREAD / float(samples);
}

SkySums sky_sums(GpuLight L, vec3 p, vec3 n, vec3 geo_n, GlossyLobe lobe, vec3 v, bool lobe_seen) {
    SkySums s = SkySums(vec4(0.0), vec2(0.0));
    int samples = int(L.params.z);
    float a2 = sky_lobe_a2(lobe, max(samples, 1));
    GlossyFresnel fresnel = glossy_fresnel_rows(u_material_lut, lobe.material, lobe.mu, lobe.base);
    for (int k = 0; k < samples; k += max(u_sky_stride, 1)) {
        vec3 d;
        vec2 w;
        if (!sky_weights(L, k, n, geo_n, lobe, fresnel, a2, v, lobe_seen, d, w)) continue;
        s.weights.xy += w;
        float gap;
        float seen = view_test(int(L.params.y) + k, p, geo_n, d, 0.0, gap);
        sky_count(s, int(L.params.y) + k, w, seen, gap, 1.0);
    }
    return s;
}

// (share of the cosine weight, of the lobe's, the penumbra's half-width in metres). The penumbra: a direction's cone
// (half-width √(4π/K)/2) at the blockers' distance, the width over which each of its hard shadows' edges should fade
// (direct/sky_filter.glsl); their harmonic mean, so that a receiver beside a wall (many blockers near) keeps the
// contact shadow the wall casts rather than the far blockers' wide fade. Sums updated after a move may hold the
// rounding of what was taken out: a blocked weight below 1e-6 of the whole counts as none, a share at most 1.
vec3 sky_result(SkySums s, int samples) {
    if (samples == 0) return vec3(1.0, 1.0, 0.0);
    bool blocked = s.penumbra.x > 0.0 && s.penumbra.y > 1e-6 * s.weights.x;
    return vec3(s.weights.x > 0.0 ? min(s.weights.z / s.weights.x, 1.0) : 0.0,
                s.weights.y > 0.0 ? min(s.weights.w / s.weights.y, 1.0) : 0.0,
                blocked ? 0.5 * sqrt(4.0 * PI / float(samples)) * s.penumbra.y / s.penumbra.x : 0.0);
}

#if defined(MODE_SKY)
// After an object's move (direct/sky.py SkyUpdate): per direction k, the box of the texels its redraw changed
// (sky_redrawn[2k]: x0, y0, x1, y1 in atlas texels, empty where it changed none) and where those its redrawn
// rectangle overwrote were kept (sky_redrawn[2k + 1]: its first index in old_texels, width, x, y).
layout(std430, binding = 11) readonly buffer SkyRedrawn { ivec4 sky_redrawn[]; };
layout(std430, binding = 12) readonly buffer OldTexels { float old_texels[]; };

// Per 8 × 8 block of pixels (a work group), which directions' rectangles its points can read (direct/sky_tiles.glsl):
// one bit per direction, u_sky_words words per block. Projecting every pixel into every one of the hundreds of views
// to find the few tests that read a redrawn texel cost as much as doing every test.
layout(std430, binding = 13) readonly buffer SkyTiles { uint sky_tile_bits[]; };
uniform int u_tiles_x;
uniform int u_sky_words;

// The sums of one update ago with the tests that read a redrawn texel done again: each such test's old result, from
// the kept texels (and the unchanged ones beside them), taken out, and its new one added.
SkySums sky_sums_update(SkySums s, GpuLight L, vec3 p, vec3 n, vec3 geo_n, GlossyLobe lobe, vec3 v, bool lobe_seen) {
    int samples = int(L.params.z);
    float a2 = sky_lobe_a2(lobe, max(samples, 1));
    GlossyFresnel fresnel = glossy_fresnel_rows(u_material_lut, lobe.material, lobe.mu, lobe.base);
    ivec2 size = textureSize(u_shadow_depth, 0);
    int first_word = (int(gl_WorkGroupID.y) * u_tiles_x + int(gl_WorkGroupID.x)) * u_sky_words;
    for (int word = 0; word < u_sky_words; ++word)
    for (uint bits = sky_tile_bits[first_word + word]; bits != 0u; bits &= bits - 1u) {
        int k = 32 * word + findLSB(bits);
        ivec4 r = sky_redrawn[2 * k];
        int view = int(L.params.y) + k;
        ShadowView sv = shadow_views[view];
        vec3 d = sv.emitter.xyz;
        vec2 atlas_uv;
        float depth;
        if (!view_uv_depth_biased(sv, p, geo_n, d, 0.0, atlas_uv, depth)) continue;
        ivec2 t0 = ivec2(floor(gather_point(sv, atlas_uv) * vec2(size) - 0.5));
        if (t0.x + 1 < r.x || t0.x >= r.z || t0.y + 1 < r.y || t0.y >= r.w) continue;   // reads no redrawn texel
        vec2 w;
        if (!sky_weights(L, k, n, geo_n, lobe, fresnel, a2, v, lobe_seen, d, w)) continue;
        ivec4 kept = sky_redrawn[2 * k + 1];
        float nearest = 2.0;
        for (int i = 0; i < 4; ++i) {
            ivec2 t = t0 + ivec2(i & 1, i >> 1);
            bool redrawn = all(greaterThanEqual(t, r.xy)) && all(lessThan(t, r.zw));
            nearest = min(nearest, redrawn ? old_texels[kept.x + (t.y - kept.w) * kept.y + t.x - kept.z]
                                           : texelFetch(u_shadow_depth, t, 0).r);
        }
        float gap_old = depth - nearest;
        sky_count(s, view, w, gap_old <= 0.0 ? 1.0 : 0.0, gap_old, -1.0);
        float gap = gather_gap(sv, atlas_uv, depth);   // view_test's, from the projection above
        sky_count(s, view, w, gap <= 0.0 ? 1.0 : 0.0, gap, 1.0);
    }
    return s;
}
#endif

// The shares of sky light L at p (sky_result), every direction tested.
vec2 sky_shares(GpuLight L, vec3 p, vec3 n, vec3 geo_n, GlossyLobe lobe, vec3 v, bool lobe_seen,
                out float penumbra) {
    vec3 r = sky_result(sky_sums(L, p, n, geo_n, lobe, v, lobe_seen), int(L.params.z));
    penumbra = r.z;
    return r.xy;
}
