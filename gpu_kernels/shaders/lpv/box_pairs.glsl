// SPDX-License-Identifier: GPL-3.0-or-later
// Which (source, receiver) pairs of the cached transport a geometry edit can change through their visibility
// (lpv/transfer.box_pairs): those whose segment passes through a box around the cells the edit changed. One bit per
// pair, 32 receivers to a word: mask[(j − first) · words + w] bit b = receiver 32w + b, source j.
layout(local_size_x = 64) in;
#include "common/structs.glsl"
layout(std430, binding = 6) readonly buffer VplList { Vpl vpls[]; };
// lpv/receivers.py: receivers[2i + 1] is receiver i's surfaces' centroid (where lpv/gather.glsl's kernel starts)
layout(std430, binding = 10) readonly buffer Receivers { vec4 receivers[]; };
layout(std430, binding = 8) writeonly buffer Mask { uint mask[]; };
// per word of 32 receivers: the box around their centroids (lo, hi; lpv/transfer_update.word_spans)
layout(std430, binding = 7) readonly buffer WordSpans { vec4 spans[]; };
uniform int u_surface_count;
uniform int u_words;
uniform int u_vpl_first;
uniform int u_vpl_count;
#define MAX_BOXES 9   // lpv/transfer_update.MAX_BOXES + 1
uniform int u_box_count;
uniform vec3 u_box_lo[MAX_BOXES];   // [0]: the box around all the others, tested first (most pairs miss it)
uniform vec3 u_box_hi[MAX_BOXES];
uniform float u_margin;             // metres the boxes are widened by for the word test (float rounding)

bool slab(vec3 a, vec3 inv, vec3 lo, vec3 hi) {  // the segment a → a + 1/inv meets the box lo..hi
    vec3 t0 = (lo - a) * inv, t1 = (hi - a) * inv;
    float enter = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z));
    float leave = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z));
    return enter <= leave && leave >= 0.0 && enter <= 1.0;
}

// Whether a segment from a to any point of the box lo..hi can meet one of the boxes 1 … count − 1: the segments lie
// in the box around a and lo..hi, so one that misses every box tested here crosses none (conservative).
bool near_box(vec3 a, vec3 lo, vec3 hi) {
    vec3 l = min(a, lo) - u_margin, h = max(a, hi) + u_margin;
    for (int k = 1; k < u_box_count; ++k)
        if (all(lessThanEqual(l, u_box_hi[k])) && all(greaterThanEqual(h, u_box_lo[k]))) return true;
    return false;
}

bool crosses_box(vec3 a, vec3 b) {  // the segment a → b meets one of the boxes 1 … count − 1
    vec3 d = b - a;
    vec3 inv = vec3(d.x != 0.0 ? 1.0 / d.x : 1e30, d.y != 0.0 ? 1.0 / d.y : 1e30, d.z != 0.0 ? 1.0 / d.z : 1e30);
    if (!slab(a, inv, u_box_lo[0], u_box_hi[0])) return false;
    for (int k = 1; k < u_box_count; ++k)
        if (slab(a, inv, u_box_lo[k], u_box_hi[k])) return true;
    return false;
}

void main() {  // one invocation per (source, word of 32 receivers)
    int id = int(gl_GlobalInvocationID.x);
    if (id >= u_vpl_count * u_words) return;
    int j = u_vpl_first + id / u_words, w = id % u_words;
    vec3 a = vpls[j].position.xyz;
    uint bits = 0u;
    if (!near_box(a, spans[2 * w].xyz, spans[2 * w + 1].xyz)) {  // most words of a small edit: skip 32 tests
        mask[id] = bits;
        return;
    }
    for (int b = 0; b < 32; ++b) {
        int i = 32 * w + b;
        if (i < u_surface_count && crosses_box(a, receivers[2 * i + 1].xyz)) bits |= 1u << uint(b);
    }
    mask[id] = bits;
}
