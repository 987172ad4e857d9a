// SPDX-License-Identifier: GPL-3.0-or-later
// Unshadowed light evaluation shared by direct lighting and RSM flux (one implementation of Cycles' light units).
#pragma once
#include "common/lights.glsl"
#include "common/polygon.glsl"

const float PI = 3.14159265358979;

// Smith's Λ for GGX (Heitz 2014, "Understanding the masking-shadowing function"): G2 = 1 / (1 + Λ(μ_v) + Λ(μ_l)).
float ggx_lambda(float alpha2, float mu) {
    float tan2 = max(1.0 / max(mu * mu, 1e-12) - 1.0, 0.0);
    return 0.5 * (sqrt(1.0 + alpha2 * tan2) - 1.0);
}

// Cycles (kernel/light/spot.h): smoothstep(0, 1, (cos α − cos(half size)) · smooth), smooth = 1/((1−cos half)·blend);
// `dir` is the unit direction from the light to the point.
float spot_attenuation(GpuLight L, vec3 dir) {
    float c = dot(dir, L.direction.xyz);
    return L.params.x > 0.0 ? smoothstep(0.0, 1.0, (c - L.direction.w) * L.params.x) : float(c > L.direction.w);
}

// Cube of six views around an origin (+X, -X, +Y, -Y, +Z, -Z): pick the face the direction falls in.
int cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x > 0.0 ? 0 : 1;
    if (a.y >= a.z) return d.y > 0.0 ? 2 : 3;
    return d.z > 0.0 ? 4 : 5;
}

// ∫ over the polygon of cosθ dω (projected solid angle), polygon clipped to the upper hemisphere of n.
// Lambert's formula: Σ_edges angle(v_i, v_j) · n·normalize(v_i × v_j) / 2 (Arvo 1995, "Applications of irradiance
// tensors"), with atan2 for the edge angle so short edges stay accurate.
float polygon_projected_solid_angle(int first, int count, vec3 p, vec3 n) {
    vec3 clipped[MAX_POLYGON_VERTICES];
    int m = 0;
    // A receiver in the polygon's own plane (e.g. the emitter itself) sees it edge-on: zero projected solid angle.
    float max_height = 0.0, max_dist = 0.0;
    for (int i = 0; i < count; ++i) {
        vec3 a = polygon_vertices[first + i].xyz - p;
        max_height = max(max_height, dot(a, n));
        max_dist = max(max_dist, length(a));
    }
    if (max_height <= 1e-5 * max_dist) return 0.0;
    for (int i = 0; i < count; ++i) {
        vec3 a = polygon_vertices[first + i].xyz - p;
        vec3 b = polygon_vertices[first + (i + 1) % count].xyz - p;
        float ha = dot(a, n), hb = dot(b, n);
        if (ha >= 0.0 && m < MAX_POLYGON_VERTICES) clipped[m++] = a;
        if ((ha >= 0.0) != (hb >= 0.0) && m < MAX_POLYGON_VERTICES) clipped[m++] = a + (b - a) * (ha / (ha - hb));
    }
    if (m < 3) return 0.0;
    float sum = 0.0;
    for (int i = 0; i < m; ++i) sum += lambert_edge(clipped[i], clipped[(i + 1) % m], n);
    return abs(sum) * 0.5;
}

// A polygon light as triangles, whatever its layout (lights.glsl, GpuLight.polygon): a fan over one polygon's
// vertices, or an emitter cluster's list; `scale` is the triangle's radiance relative to color_type.rgb (rgb) and
// 1 where it emits along its winding normal (b − a) × (c − a) only (w: a closed emitter's, common/emitters.py). For
// code that integrates something other than the cosine over the light (a glossy lobe).
// NO_TRIANGLE_LISTS (direct/shadows.ShadowAtlas.defines: the scene has no emissive mesh) leaves the triangle
// lists' code out of the program: unused, it still made llvmpipe run an area light's RSM texels about twice as long.
int polygon_triangle_count(GpuLight L) {
#if defined(NO_TRIANGLE_LISTS)
    return max(int(L.polygon.y) - 2, 0);
#else
    return L.polygon.w > 0.5 ? int(L.polygon.y) / 4 : max(int(L.polygon.y) - 2, 0);
#endif
}

void polygon_triangle(GpuLight L, int t, out vec3 a, out vec3 b, out vec3 c, out vec4 scale) {
    int first = int(L.polygon.x);
#if !defined(NO_TRIANGLE_LISTS)
    if (L.polygon.w > 0.5) {
        a = polygon_vertices[first + 4 * t].xyz;
        b = polygon_vertices[first + 4 * t + 1].xyz;
        c = polygon_vertices[first + 4 * t + 2].xyz;
        scale = polygon_vertices[first + 4 * t + 3];
        return;
    }
#endif
    a = polygon_vertices[first].xyz;
    b = polygon_vertices[first + t + 1].xyz;
    c = polygon_vertices[first + t + 2].xyz;
    scale = vec4(1.0, 1.0, 1.0, 0.0);
}

// A polygon light's ∫ (radiance / color) cosθ dω at p: its polygon's projected solid angle, or for a triangle list
// (an emitter cluster, polygon.w = 1) the sum over its triangles, each weighted by its own relative radiance, a
// one-sided one only where p lies on the side it emits to. A point within SELF_PLANE of a triangle's size of its
// plane, over the triangle (not within 1e-3 of its edges: a wall's point beside a corner is over the edge of the
// wall it meets, which lights it), lies on it: from just off its plane a triangle fills half the sky, and a position
// rasterised on the emitter itself at a grazing angle is up to 1e-3 of its size off (measured: a lamp shade's RSM
// texels lit themselves, the shade's first bounce 2.6× what the room reflected). Irradiance = color_type.rgb × this.
#define SELF_PLANE 1e-2
#if !defined(NO_TRIANGLE_LISTS)
// The triangle list's triangle at polygon_vertices[i] (vertices relative to p, its relative radiance), false where p
// gets none of its light: behind a one-sided triangle, or on it.
bool emitter_triangle_seen(int i, vec3 p, out vec3 a, out vec3 b, out vec3 c, out vec3 scale) {
    a = polygon_vertices[i].xyz - p;
    b = polygon_vertices[i + 1].xyz - p;
    c = polygon_vertices[i + 2].xyz - p;
    vec4 s = polygon_vertices[i + 3];
    scale = s.rgb;
    vec3 tn = cross(b - a, c - a);
    float len = length(tn);
    float height = -dot(a, tn) / max(len, 1e-30);   // p above the triangle's plane, along its winding normal
    if (s.w > 0.5 && height < 0.0) return false;   // behind a one-sided triangle
    if (abs(height) <= SELF_PLANE * sqrt(0.5 * len)) {   // on its plane: on it, if over it (barycentrics > 1e-3)
        vec3 edges = vec3(dot(cross(b - a, -a), tn), dot(cross(c - b, -b), tn), dot(cross(a - c, -c), tn));
        if (min(edges.x, min(edges.y, edges.z)) > 1e-3 * len * len) return false;
    }
    return true;
}
#endif

vec3 polygon_light_solid_angle(GpuLight L, vec3 p, vec3 n) {
    int first = int(L.polygon.x), count = int(L.polygon.y);
#if defined(NO_TRIANGLE_LISTS)
    return vec3(polygon_projected_solid_angle(first, count, p, n));
#else
    if (L.polygon.w < 0.5) return vec3(polygon_projected_solid_angle(first, count, p, n));
    vec3 sum = vec3(0.0);
    for (int i = first; i < first + count; i += 4) {
        vec3 a, b, c, scale;
        if (emitter_triangle_seen(i, p, a, b, c, scale)) sum += triangle_projected_solid_angle(a, b, c, n) * scale;
    }
    return sum;
#endif
}

// polygon_light_solid_angle for n (returned) and −n (`back`) at once: a triangle list's triangles are evaluated once
// for both sides (triangle_projected_solid_angles), a single polygon twice.
vec3 polygon_light_solid_angles(GpuLight L, vec3 p, vec3 n, out vec3 back) {
    int first = int(L.polygon.x), count = int(L.polygon.y);
#if !defined(NO_TRIANGLE_LISTS)
    if (L.polygon.w >= 0.5) {
        vec3 front = vec3(0.0);
        back = vec3(0.0);
        for (int i = first; i < first + count; i += 4) {
            vec3 a, b, c, scale;
            if (!emitter_triangle_seen(i, p, a, b, c, scale)) continue;
            vec2 both = triangle_projected_solid_angles(a, b, c, n);
            front += both.x * scale;
            back += both.y * scale;
        }
        return front;
    }
#endif
    back = vec3(polygon_projected_solid_angle(first, count, p, -n));
    return vec3(polygon_projected_solid_angle(first, count, p, n));
}

