// SPDX-License-Identifier: GPL-3.0-or-later
// The per-pixel sub-rays' hits, and the bounce gathers' steps, recorded once and replayed after a light, world or
// material colour edit (vct/replay.py).
//
// Why it is exact: with the geometry, the camera and the trace settings fixed, everything a sub-ray does but the
// radiance it reads depends on the volumes' optical depths and the layer volume alone (vct/crossing.glsl): where it
// steps, which texels it crosses, how much of it each crossing absorbs (α = min(1 − e^−τ, T_j)). A light edit
// changes the volumes' τ·S and nothing else, so a pixel's Diffuse Indirect is the same sum of the same terms,
// (1/N)·α·(τ·S)/τ read at the same point of the same volume and level, per cone, weighted by the cone's w — the
// cached "per-receiver weights of each cone sample" of Enlighten-style precomputed transport, kept per pixel.
// A replay sums them in the order the trace did, so it gives the trace's image bit for bit.
//
// Layout: each traced texel's hits in chunks of HIT_CHUNK slots taken from a shared pool with an atomic counter
// (binding 3; the counter goes on past the pool's capacity, so the pass that recorded knows how many it needed);
// a chunk's slots hold (q.xyz, α) and a tag (cone | volume << 5 | level << 8), the chunk after it is `next`.
// header = (first chunk, hits, the texel's AO bits, state): state 1 recorded, 2 background, 0 not recorded (the
// pool ran out: a replay traces that texel again).
#pragma once
#if defined(MODE_RECORD) || defined(MODE_REPLAY) || defined(MODE_RECORD_GATHER) || defined(MODE_REPLAY_GATHER)

#define HIT_CHUNK 16u
#define HIT_RECORDED 1u
#define HIT_BACKGROUND 2u
#define HIT_FULL 0xffffffffu

layout(std430, binding = 3) buffer HitCount { uint chunk_count; };
layout(std430, binding = 4) buffer HitHeaders { uvec4 hit_headers[]; };
layout(std430, binding = 7) buffer HitNext { uint hit_next[]; };        // per chunk
uniform uint u_chunk_capacity;

#if defined(MODE_RECORD) || defined(MODE_RECORD_GATHER)
int g_cone = 0;            // the cone being traced (vct/common.glsl gather_irradiance sets it)
int g_chunk = -1;          // this item's current chunk
uint g_first = 0u, g_slot = 0u, g_hits = 0u;
bool g_overflow = false;

// The slot for this item's next record, or HIT_FULL once the pool has run out (the item is then not kept).
uint hit_slot() {
    if (g_overflow) return HIT_FULL;
    if (g_chunk < 0 || g_slot == HIT_CHUNK) {
        uint c = atomicAdd(chunk_count, 1u);
        if (c >= u_chunk_capacity) {
            g_overflow = true;
            return HIT_FULL;
        }
        if (g_chunk < 0) g_first = c;
        else hit_next[g_chunk] = c;
        g_chunk = int(c);
        g_slot = 0u;
    }
    g_hits += 1u;
    return uint(g_chunk) * HIT_CHUNK + g_slot++;
}
#endif

// The slot of an item's h-th record, walking its chunks (`chunk`: the chunk of record h − 1, then of record h).
uint hit_at(uint h, inout uint chunk) {
    if (h > 0u && h % HIT_CHUNK == 0u) chunk = hit_next[chunk];
    return chunk * HIT_CHUNK + h % HIT_CHUNK;
}

#if defined(MODE_RECORD) || defined(MODE_REPLAY)
// The per-pixel sub-rays' hits (vct/trace.glsl).
layout(std430, binding = 5) buffer HitPoints { vec4 hit_points[]; };   // q (texture coordinates), α
layout(std430, binding = 6) buffer HitTags { uint hit_tags[]; };       // cone | volume << 5 | level << 8
#endif

#if defined(MODE_RECORD)
void record_hit(vec3 q, float lod, int volume, float alpha) {
    uint i = hit_slot();
    if (i == HIT_FULL) return;
    hit_points[i] = vec4(q, alpha);
    hit_tags[i] = uint(g_cone) | (uint(volume) << 5) | (uint(lod) << 8);
}
#endif

#if defined(MODE_REPLAY) || defined(MODE_REPLAY_GATHER)
// The six volumes again, on u_volume's units (vct/volumes.bind_volumes), read through a switch: the volume differs
// between lanes (vct/arrays.glsl). Through a switch of u_volume's own elements, llvmpipe (Mesa 22) got the
// dynamically indexed u_volume reads of the items a replay marches again wrong.
uniform sampler3D u_replay0, u_replay1, u_replay2, u_replay3, u_replay4, u_replay5;
vec4 volume_at(uint i, vec3 q, float lod) {
    switch (i) {
        case 0u: return textureLod(u_replay0, q, lod); case 1u: return textureLod(u_replay1, q, lod);
        case 2u: return textureLod(u_replay2, q, lod); case 3u: return textureLod(u_replay3, q, lod);
        case 4u: return textureLod(u_replay4, q, lod); default: return textureLod(u_replay5, q, lod);
    }
}

// A replay's cones up to (not including) `until` are done: each adds its weight times its radiance to e, in cone
// order, as gather_irradiance does (vct/common.glsl).
void end_cones(inout vec3 e, inout vec3 radiance, inout int cone, int until) {
    for (; cone < until; ++cone) {
        e += u_cones[cone].w * radiance;
        radiance = vec3(0.0);
    }
}
#endif

#if defined(MODE_RECORD_GATHER) || defined(MODE_REPLAY_GATHER)
// The bounce gathers' steps that absorbed part of their cone (vct/common.glsl trace_cone, cone_step): where the
// step read (uvw, level), the axes' weights and optical depth it read there, its opacity α and the cone's
// transmittance T before it, and (cone | the three volumes read << 5) as float bits.
struct GatherStep { vec4 uvw_lod; vec4 w_tau; vec4 alpha_t_tag; };
layout(std430, binding = 6) buffer GatherSteps { GatherStep gather_steps[]; };
#endif
#endif
