// SPDX-License-Identifier: GPL-3.0-or-later
// VCT radiance injection from real surface points (Freed 2018, §4.3, injects the lit surface points of the shadow map;
// here every surface point is rasterised, lit or not, so shadowed faces get their 0 too).
//
// Geometry shader: each triangle is projected along the dominant axis of its normal (Freed 2018, §4.1.1, Algorithm 1)
// onto a plane of VCT_SAMPLES pixels per voxel edge; every fragment is a point p on the surface, with the
// triangle's geometric normal n.
// Fragment shader: for each side s = ±n the irradiance E_s = E(p, s·n) of every light exactly as the Diffuse Direct
// pass computes it (direct/eval.glsl; closed emitters emit outwards only, common/emitters.py). The side's light
// leaves the voxel through the faces its normal points to: face g = (axis b, sign of s·n_b) receives weight
// w = A·|n_b| (the fragment's area A projected onto that face's plane) and adds w·E_s/π, w and w·p to the face's
// accumulator (vct/inject.glsl resolves the means). So a voxel holding a floor and a wall (an edge) gets the lit
// wall's light on its ±x faces and the floor's on its ±z faces, wherever their surfaces lie in the voxel — the
// voxel's mean normal could not say which side of such a voxel faces the room.
// MODE_ALBEDO adds w·albedo and w instead, for the same points and weights (the material's albedo as the voxelizer
// defines it, voxel/common.glsl voxel_albedo: the diffuse and glossy layers' reflectance averaged over directions):
// the face's albedo, kept apart from its light so that a material's colour edit changes the one and not the other
// (vct/face_albedo.glsl; the face's radiance is albedo_g ⊙ E_g/π, vct/inject_sum.glsl).
// Covered surfaces: a surface with another one in front of it in the same raster column of the same voxel (the
// floor under a rug lying 1 mm above it, a wall behind a poster) is hidden from that side and leaves the face of
// that side alone, so the visible surface's colour is the face's. A first pass (MODE_FRONT) keeps, per column,
// voxel and side of the dominant axis, the front-most surface's depth; only the covered side is left out (the
// floor's underside still faces down).
// No float atomics in GL 4.5: the adds are compare-and-swap loops on the float's bits (r32ui).
#if defined(VERTEX_SHADER)
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;
out vec3 v_world;
out vec2 v_uv;
void main() {
    v_world = in_position;
    v_uv = in_uv;
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
#endif

#if defined(GEOMETRY_SHADER)
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
in vec3 v_world[];
in vec2 v_uv[];
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform float u_samples;       // pixels per voxel edge
uniform vec2 u_viewport;       // framebuffer size in pixels
out vec3 g_world;
out vec2 g_uv;
flat out vec3 g_normal;        // unit geometric normal
flat out float g_area;         // surface area (m²) one fragment stands for: (cell/samples)² / |n_dominant|
flat out int g_axis;           // the dominant axis the triangle is rasterised along

vec3 to_plane(vec3 p, int axis) { return axis == 0 ? p.yzx : (axis == 1 ? p.zxy : p); }

void main() {
    vec3 n = cross(v_world[1] - v_world[0], v_world[2] - v_world[0]);
    float len = length(n);
    if (!(len > 0.0)) return;
    n /= len;
    vec3 an = abs(n);
    int axis = (an.x >= an.y && an.x >= an.z) ? 0 : (an.y >= an.z ? 1 : 2);
    float px = u_grid_cell / u_samples;
    for (int i = 0; i < 3; ++i) {
        vec2 q = to_plane((v_world[i] - u_grid_origin) / px, axis).xy;
        gl_Position = vec4(q / u_viewport * 2.0 - 1.0, 0.0, 1.0);
        g_world = v_world[i];
        g_uv = v_uv[i];
        g_normal = n;
        g_area = px * px / an[axis];
        g_axis = axis;
        EmitVertex();
    }
    EndPrimitive();
}
#endif

#if defined(FRAGMENT_SHADER)
#if !defined(MODE_ALBEDO)
#include "common/lights.glsl"
#include "common/light_eval.glsl"
#include "direct/eval.glsl"
uniform int u_light_count;
#endif
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform ivec3 u_grid_size;
uniform vec3 u_base_color;
uniform vec3 u_albedo_scale;      // common/principled.py: transport_albedo, albedo = base ⊙ scale + offset
uniform vec3 u_albedo_offset;
uniform bool u_use_texture;
uniform sampler2D u_base_texture;
in vec3 g_world;
in vec2 g_uv;
flat in vec3 g_normal;
flat in float g_area;
flat in int g_axis;
uniform bool u_cover_test;        // the front-most images are bound (they fit the memory budget, vct/inject.py)
// Per voxel column (the fragment's pixel) and side: the front-most depth, layer 2k (+axis) and 2k + 1 (−axis) of
// voxel layer k, in 1/65535 of a cell, larger = further out along that side.
layout(r32ui, binding = 1) coherent uniform uimage3D u_front_x;
layout(r32ui, binding = 2) coherent uniform uimage3D u_front_y;
layout(r32ui, binding = 3) coherent uniform uimage3D u_front_z;
#define FRONT_TOLERANCE 66u         // 1/1000 of a cell: coplanar pieces (shared edges, duplicates) all count
// Accumulator: channel c (0–2 Σw·E/π or, MODE_ALBEDO, Σw·albedo; 3 Σw; 4–6 Σw·p, not in MODE_ALBEDO) of face g of
// voxel v at (ACC_CHANNELS·v.x + c, v.y, g·nz + v.z); ACC_CHANNELS is defined by vct/inject.py (LIGHT_SUMS or
// ALBEDO_SUMS).
layout(r32ui, binding = 0) coherent uniform uimage3D u_acc;

void add_float(ivec3 t, float x) {
    if (x == 0.0) return;
    uint expected = imageLoad(u_acc, t).r;
    for (int i = 0; i < 256; ++i) {
        uint actual = imageAtomicCompSwap(u_acc, t, expected, floatBitsToUint(uintBitsToFloat(expected) + x));
        if (actual == expected) return;
        expected = actual;
    }
}

ivec3 front_texel(ivec3 v, int s) {
    return ivec3(ivec2(gl_FragCoord.xy), 2 * v[g_axis] + s);
}

// How far out along side s (0: +axis, 1: −axis) of its voxel the point lies.
uint front_depth(vec3 p, ivec3 v, int s) {
    float f = clamp((p[g_axis] - u_grid_origin[g_axis]) / u_grid_cell - float(v[g_axis]), 0.0, 1.0);
    return uint((s == 0 ? f : 1.0 - f) * 65535.0 + 0.5);
}

uint front_load(ivec3 t) {
    return g_axis == 0 ? imageLoad(u_front_x, t).r : (g_axis == 1 ? imageLoad(u_front_y, t).r : imageLoad(u_front_z, t).r);
}

void front_max(ivec3 t, uint d) {
    if (g_axis == 0) imageAtomicMax(u_front_x, t, d);
    else if (g_axis == 1) imageAtomicMax(u_front_y, t, d);
    else imageAtomicMax(u_front_z, t, d);
}

// Adds w·value, w (and, lighting, w·p) to each face of voxel v that the side with normal n leaves through, unless
// a surface in front of p in its raster column covers that side.
void deposit(vec3 p, ivec3 v, vec3 n, vec3 value) {
    for (int b = 0; b < 3; ++b) {
        float w = g_area * abs(n[b]);
        if (w <= 0.0) continue;
        if (u_cover_test && b == g_axis) {
            int s = n[b] > 0.0 ? 0 : 1;
            if (front_depth(p, v, s) + FRONT_TOLERANCE < front_load(front_texel(v, s))) continue;  // covered
        }
        int g = 2 * b + (n[b] > 0.0 ? 0 : 1);
        ivec3 t = ivec3(ACC_CHANNELS * v.x, v.y, g * u_grid_size.z + v.z);
        add_float(t, w * value.r);
        add_float(t + ivec3(1, 0, 0), w * value.g);
        add_float(t + ivec3(2, 0, 0), w * value.b);
        add_float(t + ivec3(3, 0, 0), w);
#if !defined(MODE_ALBEDO)
        add_float(t + ivec3(4, 0, 0), w * p.x);
        add_float(t + ivec3(5, 0, 0), w * p.y);
        add_float(t + ivec3(6, 0, 0), w * p.z);
#endif
    }
}

void main() {
    vec3 p = g_world;
    ivec3 v = ivec3(floor((p - u_grid_origin) / u_grid_cell));
    if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, u_grid_size))) return;
#if defined(MODE_FRONT)
    front_max(front_texel(v, 0), front_depth(p, v, 0));
    front_max(front_texel(v, 1), front_depth(p, v, 1));
    return;
#endif
#if defined(MODE_ALBEDO)
    vec3 color = u_use_texture ? textureLod(u_base_texture, g_uv, 0.0).rgb : u_base_color;
    vec3 albedo = max(color, vec3(0.0)) * u_albedo_scale + u_albedo_offset;
    deposit(p, v, g_normal, albedo);
    deposit(p, v, -g_normal, albedo);
#else
    // Both sides lit in one pass over the lights (light_unshadowed_sides: an emissive mesh's triangles once for the
    // two), each side's irradiance summed over the lights in their order as light_irradiance would.
    vec3 lit[2] = vec3[2](vec3(0.0), vec3(0.0));
    for (int i = 0; i < u_light_count; ++i) {
        vec3 back, front = light_unshadowed_sides(lights[i], p, g_normal, back);
        if (max(front.r, max(front.g, front.b)) > 0.0)
            lit[0] += front * light_visibility(lights[i], p, g_normal, g_normal);
        if (max(back.r, max(back.g, back.b)) > 0.0)
            lit[1] += back * light_visibility(lights[i], p, -g_normal, -g_normal);
    }
    deposit(p, v, g_normal, lit[0] / PI);
    deposit(p, v, -g_normal, lit[1] / PI);
#endif
}
#endif
