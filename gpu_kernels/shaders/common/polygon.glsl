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

// The part of edge a→b above the plane (heights ha, hb), appended to q (one Sutherland–Hodgman step).
void clip_edge(vec3 a, vec3 b, float ha, float hb, inout vec3 q[4], inout int m) {
    if (ha >= 0.0 && m < 4) q[m++] = a;
    if ((ha >= 0.0) != (hb >= 0.0) && m < 4) q[m++] = a + (b - a) * (ha / (ha - hb));
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
