// SPDX-License-Identifier: GPL-3.0-or-later
// The projected solid angle of polygons (Lambert's formula), for lights (common/light_eval.glsl) and for the LPV's
// near-field sources (lpv/gather.glsl): nothing here reads a buffer.
#pragma once

// One edge's term of Lambert's formula, angle(a, b) · n·normalize(a × b), for a, b relative to the receiver; atan2
// for the angle so short edges stay accurate.
float lambert_edge(vec3 a, vec3 b, vec3 n) {
    a = normalize(a);
    b = normalize(b);
    vec3 c = cross(a, b);
    float s = length(c);
    return s < 1e-12 ? 0.0 : atan(s, dot(a, b)) * dot(n, c) / s;
}

vec3 cut(vec3 a, vec3 b, float ha, float hb) {  // where edge a→b crosses the plane (heights ha, hb of opposite sign)
    return a + (b - a) * (ha / (ha - hb));
}

// The part of edge a→b above the plane (heights ha, hb), appended to q (one Sutherland–Hodgman step).
void clip_edge(vec3 a, vec3 b, float ha, float hb, inout vec3 q[4], inout int m) {
    if (ha >= 0.0 && m < 4) q[m++] = a;
    if ((ha >= 0.0) != (hb >= 0.0) && m < 4) q[m++] = cut(a, b, ha, hb);
}

// polygon_projected_solid_angle of one triangle (vertices relative to the receiver), without loops: an emitter
// cluster holds many, and llvmpipe caps a shader invocation's loop iterations (docs/conventions.md).
float triangle_projected_solid_angle(vec3 a, vec3 b, vec3 c, vec3 n) {
    float ha = dot(a, n), hb = dot(b, n), hc = dot(c, n);
    if (max(ha, max(hb, hc)) <= 1e-5 * max(length(a), max(length(b), length(c)))) return 0.0;
    vec3 q[4];
    int m = 0;
    clip_edge(a, b, ha, hb, q, m);
    clip_edge(b, c, hb, hc, q, m);
    clip_edge(c, a, hc, ha, q, m);
    if (m < 3) return 0.0;
    float sum = lambert_edge(q[0], q[1], n) + lambert_edge(q[1], q[2], n);
    sum += m == 4 ? lambert_edge(q[2], q[3], n) + lambert_edge(q[3], q[0], n) : lambert_edge(q[2], q[0], n);
    return abs(sum) * 0.5;
}

// The part of quad q0…q3 above a plane (corner heights u), as a quad: where no corner or two adjacent ones lie below
// (a plane across the rectangle's axis: a wall standing on a floor's rectangle); false for a triangle or pentagon.
bool clip_quad(inout vec3 q0, inout vec3 q1, inout vec3 q2, inout vec3 q3, vec4 u) {
    bvec4 below = lessThan(u, vec4(0.0));
    if (!any(below)) return true;
    vec3 r0 = q0, r1 = q1, r2 = q2, r3 = q3;
    if (below == bvec4(true, true, false, false)) { q0 = cut(r0, r3, u.x, u.w); q1 = cut(r1, r2, u.y, u.z); }
    else if (below == bvec4(false, true, true, false)) { q1 = cut(r1, r0, u.y, u.x); q2 = cut(r2, r3, u.z, u.w); }
    else if (below == bvec4(false, false, true, true)) { q2 = cut(r2, r1, u.z, u.y); q3 = cut(r3, r0, u.w, u.x); }
    else if (below == bvec4(true, false, false, true)) { q3 = cut(r3, r2, u.w, u.z); q0 = cut(r0, r1, u.x, u.y); }
    else return false;
    return true;
}

// The projected solid angle of a quad lying wholly above the plane of n (clip_quad first), over its four edges,
// with no arrays: llvmpipe keeps arrays in memory for the whole shader.
float quad_projected_solid_angle(vec3 q0, vec3 q1, vec3 q2, vec3 q3, vec3 n) {
    return abs(lambert_edge(q0, q1, n) + lambert_edge(q1, q2, n) + lambert_edge(q2, q3, n)
               + lambert_edge(q3, q0, n)) * 0.5;
}
