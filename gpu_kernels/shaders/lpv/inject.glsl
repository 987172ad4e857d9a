// SPDX-License-Identifier: GPL-3.0-or-later
// LPV injection (Elvek 2012, §3.3; Kaplanyan 2009): every RSM texel is a VPL of flux Φ = albedo × (irradiance × texel
// area); its intensity (Φ/π)·max(0, n·ω) is projected on 2-band SH and added to the cell half a cell in front of it.
// Accumulation is exact fixed point (integer atomics; no float atomics here), scaled by u_fixed_scale. Because Φ
// carries the texel's world area, the result does not depend on the RSM resolution.
// MODE_LIST: the same VPLs are written to a list instead (two slots per block; w = 1 marks a VPL), for the gathered
// first bounce (lpv/gather.glsl).
#include "common/lights.glsl"
#include "common/light_eval.glsl"
#include "common/principled.glsl"
#include "lpv/fixed.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_rsm_position;
uniform sampler2D u_rsm_normal;
uniform sampler2D u_rsm_albedo;
uniform ivec2 u_rsm_size;
uniform int u_downsample;         // k: each k×k block of texels becomes one VPL (Kaplanyan 2009, §N.5.2)
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform ivec3 u_grid_size;
uniform sampler2D u_material_lut;  // common/principled.py: material_lut
// Per material: rgb the base colour the RSM's texel colour is multiplied by (1 where a texture gives it), w unused
// (direct/geometry.MaterialTextures.colors). With u_delta, the texels' flux is what a colour edit adds: their albedo
// at these colours less at u_old_colors' (w > 0: the material's colour changed; the other texels add nothing).
layout(std430, binding = 8) readonly buffer BaseColors { vec4 base_colors[]; };
layout(std430, binding = 10) readonly buffer OldColors { vec4 old_colors[]; };
uniform bool u_delta;

struct RsmView {
    vec4 params;   // x: tan(half fov) (perspective) or 0; y: texel world size (orthographic); z: light; w: sample k
    vec4 origin;   // xyz eye (perspective); w: 1 if orthographic
    vec4 axis;     // xyz view axis; w: texels per side of this view (lpv/rsm.view_resolution)
    vec4 right;    // xyz right vector of the view (with axis and up: tangent-plane coordinates); w: the tangent
                   // half extent the view covers alone (1 for a cube's face), 0 where it overlaps no other view
};
layout(std430, binding = 3) readonly buffer RsmViewBuffer { RsmView rsm_views[]; };
#if defined(MODE_LIST)
#include "common/structs.glsl"
layout(std430, binding = 6) writeonly buffer VplList { Vpl vpls[]; };
uniform int u_blocks_x;           // blocks per atlas row: the list slot of a block
// One dispatch covers u_block_count blocks from u_block_origin, and writes the rows of blocks from u_row_base on
// from slot u_slot_base (lpv/gather.rsm_records: the whole atlas, or the rows of the views a light edit moved).
uniform ivec2 u_block_origin;
uniform ivec2 u_block_count;
uniform int u_row_base;
uniform int u_slot_base;
// u_masked: only the lights whose light_mask is non-zero make VPLs (a light edit re-bins the lights it moved,
// lpv/passes.py first_bounce); a block's texels all belong to one view, so one test per block.
uniform bool u_masked;
layout(std430, binding = 7) readonly buffer LightMask { uint light_mask[]; };
#if defined(BLOCK_LIST)
// Listed blocks instead of a rectangle, one per invocation, block k's records in slots 2k and 2k + 1 (lpv/gather.
// rsm_records with rects: after an object's move, the blocks it covers in every view, in one dispatch).
layout(std430, binding = 11) readonly buffer BlockList { ivec2 block_list[]; };
uniform int u_list_count;
#endif
#endif
// The flux per unit of each light's colour (colour × power or strength = 1), its light's index in the record's
// flux.w (MODE_LIST): the LPV's cached transport bins each light's records once and scales them by its colour.
uniform bool u_unit_color;

// Solid angle of one texel of a perspective view with tan(half fov) m at tangent-plane point (x, y):
// (2m/res)² / (1 + x² + y²)^(3/2).
float texel_solid_angle(RsmView v, vec3 p) {
    vec3 d = p - v.origin.xyz;
    float z = dot(d, v.axis.xyz);
    vec3 up = cross(v.right.xyz, v.axis.xyz);
    float x = dot(d, v.right.xyz) / z, y = dot(d, up) / z;
    float t = 2.0 * v.params.x / v.axis.w;
    return t * t / pow(1.0 + x * x + y * y, 1.5);
}

// The share of the texel at p that belongs to its view alone: a cube's faces are rendered a few texels wider
// than 90° (common/lights.cube_views: PCF never reads past an edge), so near its edges a face sees what the next
// face sees too. Those texels' flux would count twice (a closed room got 1.017 of a point light's power): each
// texel keeps the part of its footprint, in tangent-plane coordinates, inside the face's own [−1, 1]².
float cube_share(RsmView v, vec3 p) {
    if (v.right.w <= 0.0) return 1.0;
    vec3 d = p - v.origin.xyz;
    float z = dot(d, v.axis.xyz);
    vec3 up = cross(v.right.xyz, v.axis.xyz);
    vec2 xy = abs(vec2(dot(d, v.right.xyz), dot(d, up)) / z);
    float t = 2.0 * v.params.x / v.axis.w;  // a texel's tangent-plane width
    vec2 inside = clamp((v.right.w - xy) / t + 0.5, 0.0, 1.0);
    return inside.x * inside.y;
}

// Reflected flux of a surfel at p (normal n facing the light, albedo a) seen by RSM view v.
vec3 vpl_flux(RsmView v, vec3 p, vec3 n, vec3 albedo) {
    GpuLight L = lights[int(v.params.z)];
    int type = int(L.color_type.w);
    vec3 color = u_unit_color ? vec3(1.0) : L.color_type.rgb;
    if (type == LIGHT_SUN) {
        // E·A = S·cosθ · t²/cosθ: the sun's flux through one texel of the orthographic map.
        float cosine = dot(n, -L.direction.xyz);
        return cosine > 0.0 ? albedo * color * v.params.y * v.params.y : vec3(0.0);
    }
    if (type == LIGHT_SKY) {
        // Sky direction k (ShadowView.emitter: d_k, its solid angle Ω_k) is a sun of irradiance L·Ω_k along −d_k.
        vec4 e = shadow_views[int(L.params.y) + int(v.params.w)].emitter;
        return dot(n, e.xyz) > 0.0 ? albedo * color * e.w * v.params.y * v.params.y : vec3(0.0);
    }
    if (type == LIGHT_POINT || type == LIGHT_SPOT) {
        // E·A = I·cosθ/(d²+r²) · d²Ω/cosθ = I·Ω·d²/(d²+r²): the light's flux into the texel's solid angle.
        vec3 d = p - L.position.xyz;
        float d2 = dot(d, d);
        float att = type == LIGHT_SPOT ? spot_attenuation(L, normalize(d)) : 1.0;
        return albedo * color * att * texel_solid_angle(v, p) * cube_share(v, p) * d2 / (d2 + L.position.w);
    }
    // Polygon light seen from sample point k: this RSM carries the share w_k/Σw_j of the exact irradiance, where
    // w_j = A_j · cosθ_light,j · cosθ_surface,j / d_j² (the same weights as the shadow test, direct/eval.glsl).
    // E_k·A simplifies to E · A_k · cosθ_light,k · Ω / Σw_j, with no division by the grazing cosine.
    vec3 psa = polygon_light_solid_angle(L, p, n);
    if (max(psa.r, max(psa.g, psa.b)) <= 0.0) return vec3(0.0);
    int first = int(L.params.y), per = int(L.params.w), samples = int(L.params.z);
    float wsum = 0.0, share_k = 0.0;
    int k = int(v.params.w);
    for (int j = 0; j < samples; ++j) {
        vec4 e = shadow_views[first + j * per].emitter;
        vec3 d = p - shadow_views[first + j * per].origin.xyz;
        float d2 = max(dot(d, d), 1e-8);
        vec3 w = d * inversesqrt(d2);
        float cl = e.w * max(dot(e.xyz, w), 0.0);
        wsum += cl * max(dot(n, -w), 0.0) / d2;
        if (j == k) share_k = cl;
    }
    if (wsum <= 0.0) return vec3(0.0);
    return albedo * color * psa * share_k * texel_solid_angle(v, p) * cube_share(v, p) / wsum;
}

// What a texel reflects of light from the light's direction (RSM normal.w = μ = n·l): Cycles' Diffuse and Glossy
// Color at μ, by reciprocity; a VPL has no lobe, so the glossy part leaves diffusely, as in the voxels
// (voxel/common.glsl voxel_albedo). `surface`: the RSM's texture colour and material index.
vec3 texel_albedo(vec4 surface, float mu, vec3 color) {
    int m = int(surface.w + 0.5);
    vec3 base = surface.rgb * color;
    return base * principled_diffuse(u_material_lut, m, mu) + principled_glossy(u_material_lut, m, mu, base);
}

// The albedo a texel's flux per unit albedo is multiplied by: its albedo, or with u_delta its colour edit's change.
vec3 flux_albedo(vec4 surface, float mu) {
    int m = int(surface.w + 0.5);
    vec3 now = texel_albedo(surface, mu, base_colors[m].rgb);
    if (!u_delta) return now;
    return old_colors[m].w > 0.5 ? now - texel_albedo(surface, mu, old_colors[m].rgb) : vec3(0.0);
}

// Whether a lit texel of the block is of a material whose colour changed: with u_delta, only those blocks have
// records that change.
bool block_recolored(ivec2 block) {
    for (int j = 0; j < u_downsample; ++j)
        for (int i = 0; i < u_downsample; ++i) {
            ivec2 px = block * u_downsample + ivec2(i, j);
            if (texelFetch(u_rsm_position, px, 0).w >= 0.5 &&
                old_colors[int(texelFetch(u_rsm_albedo, px, 0).w + 0.5)].w > 0.5) return true;
        }
    return false;
}

void main() {
    // Intensity-aware clustering (Kaplanyan 2009, §N.5.2): a k×k block of RSM texels becomes a VPL with the block's
    // total flux, at the mean position and normal weighted by the luminance of its flux per unit albedo — flux is kept
    // exactly, and the VPL sits where the light is. (Not by the flux itself: then a material's colour would move the
    // VPLs, and a colour edit could not re-bin the edited texels' change alone into the clusters the records went to.) A block can span two surfaces (a sunlit roof and, through its opening, the floor 3 m below): their
    // mean would float in the air between them, so texels off the plane of the block's first lit texel (normal
    // more than ~25° away, or more than half a cell from its plane) form a second VPL. Blocks never straddle views:
    // tiles are multiples of 16 texels and k divides 16.
#if defined(BLOCK_LIST)
    int item = int(gl_WorkGroupID.x) * 64 + int(gl_LocalInvocationIndex);
    if (item >= u_list_count) return;
    ivec2 block = block_list[item];
    int slot = 2 * item;
#elif defined(MODE_LIST)
    if (any(greaterThanEqual(ivec2(gl_GlobalInvocationID.xy), u_block_count))) return;
    ivec2 block = ivec2(gl_GlobalInvocationID.xy) + u_block_origin;
    int slot = u_slot_base + 2 * ((block.y - u_row_base) * u_blocks_x + block.x);
#else
    ivec2 block = ivec2(gl_GlobalInvocationID.xy);
#endif
    if (any(greaterThanEqual(block * u_downsample, u_rsm_size))) return;
    if (u_delta && !block_recolored(block)) return;
    vec3 flux[2] = vec3[2](vec3(0.0), vec3(0.0));
    vec3 position[2] = vec3[2](vec3(0.0), vec3(0.0));
    vec3 normal[2] = vec3[2](vec3(0.0), vec3(0.0));
    float weight[2] = float[2](0.0, 0.0);
    bool has_plane = false;
    vec3 plane_p = vec3(0.0), plane_n = vec3(0.0);
    float light = 0.0;  // the block's light (blocks never straddle views)
    for (int j = 0; j < u_downsample; ++j)
        for (int i = 0; i < u_downsample; ++i) {
            ivec2 px = block * u_downsample + ivec2(i, j);
            vec4 pos = texelFetch(u_rsm_position, px, 0);
            if (pos.w < 0.5) continue;
            vec4 normal_mu = texelFetch(u_rsm_normal, px, 0);
            vec3 n = normalize(normal_mu.xyz);
            if (!has_plane) {
                has_plane = true;
                plane_p = pos.xyz;
                plane_n = n;
                light = rsm_views[int(pos.w - 0.5)].params.z;
#if defined(MODE_LIST)
                if (u_masked && light_mask[int(light + 0.5)] == 0u) return;
#endif
            }
            int c = (dot(n, plane_n) > 0.9 && abs(dot(pos.xyz - plane_p, plane_n)) < 0.5 * u_grid_cell) ? 0 : 1;
            vec3 unit = vpl_flux(rsm_views[int(pos.w - 0.5)], pos.xyz, n, vec3(1.0));
            float w = dot(unit, vec3(0.2126, 0.7152, 0.0722));  // Rec.709 luminance
            flux[c] += unit * flux_albedo(texelFetch(u_rsm_albedo, px, 0), normal_mu.w);
            position[c] += w * pos.xyz;
            normal[c] += w * n;
            weight[c] += w;
        }
    for (int c = 0; c < 2; ++c) {
        if (weight[c] <= 0.0 || dot(normal[c], normal[c]) == 0.0) continue;
#if defined(MODE_LIST)
        vpls[slot + c] = Vpl(vec4(position[c] / weight[c], 1.0), vec4(normalize(normal[c]), 0.0), vec4(flux[c], light));
#else
        inject_lambertian(LpvGrid(u_grid_origin, u_grid_cell, u_grid_size), position[c] / weight[c],
                          normalize(normal[c]), flux[c]);
#endif
    }
}
