// SPDX-License-Identifier: GPL-3.0-or-later
// After an object's move (direct/sky.py): per 8 × 8 block of pixels and sky direction, whether a test at one of the
// block's points — its four texels or its cone's taps (direct/eval.glsl sky_reach) — can read a texel the
// direction's map redrew: one bit per direction, 32 to a word (direct/sky.glsl SkyTiles). One invocation per
// (block, word).
#include "direct/eval.glsl"

layout(local_size_x = 64) in;
uniform int u_first_view;    // the sky's first view
uniform int u_directions;
uniform int u_tiles;
uniform int u_words;
layout(std430, binding = 11) readonly buffer SkyRedrawn { ivec4 sky_redrawn[]; };   // direct/sky.glsl, per direction
layout(std430, binding = 13) readonly buffer Boxes { vec4 boxes[]; };   // per block: lo, hi (lo > hi: none)
layout(std430, binding = 14) writeonly buffer Bits { uint bits[]; };

// Whether a test of orthographic view v at a point of the box (centre c, half-size h, grown by the test's bias) can
// read a texel of rectangle r (a gather's 2 × 2 texels and a texel of rounding, and `taps` texels beyond): atlas
// texels are affine in the point, so the box's projection is its centre's ± Σ |∂texel/∂x_i| · h_i.
bool box_reaches(ShadowView v, vec3 c, vec3 h, ivec4 r, float taps) {
    mat4 m = v.view_projection;
    vec2 scale = 0.5 * v.tile.zw / u_atlas_texel;
    vec3 ax = scale.x * vec3(m[0][0], m[1][0], m[2][0]), ay = scale.y * vec3(m[0][1], m[1][1], m[2][1]);
    vec2 centre = v.tile.xy / u_atlas_texel + scale * (vec2(m[3][0], m[3][1]) + 1.0) + vec2(dot(ax, c), dot(ay, c));
    vec2 reach = vec2(dot(abs(ax), h), dot(abs(ay), h)) + 2.0 + taps;
    return centre.x + reach.x >= float(r.x) && centre.x - reach.x < float(r.z)
        && centre.y + reach.y >= float(r.y) && centre.y - reach.y < float(r.w);
}

void main() {
    int id = int(gl_GlobalInvocationID.x);
    if (id >= u_tiles * u_words) return;
    int tile = id / u_words, word = id % u_words;
    vec3 lo = boxes[2 * tile].xyz, hi = boxes[2 * tile + 1].xyz;
    uint out_bits = 0u;
    if (all(lessThanEqual(lo, hi))) {
        vec3 c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
        for (int b = 0; b < 32; ++b) {
            int k = 32 * word + b;
            if (k >= u_directions) break;
            ivec4 r = sky_redrawn[k];
            if (r.z <= r.x) continue;
            ShadowView v = shadow_views[u_first_view + k];
            float taps = sky_reach(u_first_view + k, u_directions);
            if (box_reaches(v, c, h + vec3(OFFSET_TEXELS * v.info.x), r, taps)) out_bits |= 1u << uint(b);
        }
    }
    bits[id] = out_bits;
}
