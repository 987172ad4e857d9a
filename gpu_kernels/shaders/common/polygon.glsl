// SPDX-License-Identifier: GPL-3.0-or-later
// The projected solid angle of polygons (Lambert's formula), for lights (common/light_eval.glsl) and for the LPV's
// near-field sources (lpv/gather.glsl): nothing here reads a buffer.
#pragma once

// One edge's term of Lambert's formula, angle(a, b) · n·normalize(a × b), for a, b relative to the receiver; atan2
// for the angle so short edges stay accurate.
float unit_lambert_edge(vec3 a, vec3 b, vec3 n) {   // a, b unit
    vec3 c = cross(a, b);
    float s = length(c);
    return s < 1e-12 ? 0.0 : atan(s, dot(a, b)) * dot(n, c) / s;
}

float lambert_edge(vec3 a, vec3 b, vec3 n) {
    return unit_lambert_edge(normalize(a), normalize(b), n);
}

vec3 cut(vec3 a, vec3 b, float ha, float hb) {  // where edge a→b crosses the plane (heights ha, hb of opposite sign)
    return a + (b - a) * (ha / (ha - hb));
}

// The piece of edge a→b above the plane (heights ha, hb; ua, ub its unit directions): its Lambert term, and where
// it leaves or enters the side above. One term an edge, its ends chosen first (llvmpipe runs both sides of a branch).
float above_unit_edge(vec3 a, vec3 b, vec3 ua, vec3 ub, float ha, float hb, vec3 n, inout vec3 enter,
                      inout vec3 leave) {
    bool crosses = (ha >= 0.0) != (hb >= 0.0);
    vec3 cp = crosses ? cut(a, b, ha, hb) : b;
    vec3 ucp = crosses ? normalize(cp) : ub;
    if (crosses && ha >= 0.0) leave = cp;
    if (crosses && ha < 0.0) enter = cp;
    float term = unit_lambert_edge(ha >= 0.0 ? ua : ucp, ha >= 0.0 ? ucp : ub, n);
    return ha >= 0.0 || crosses ? term : 0.0;
}

// polygon_projected_solid_angle of one triangle (vertices relative to the receiver), without loops: an emitter
// cluster holds many, and llvmpipe caps a shader invocation's loop iterations (docs/conventions.md). The part above
// the receiver's plane: each edge's piece above it, closed along the plane from where it leaves to where it enters.
float triangle_projected_solid_angle(vec3 a, vec3 b, vec3 c, vec3 n) {
    float ha = dot(a, n), hb = dot(b, n), hc = dot(c, n);
    if (max(ha, max(hb, hc)) <= 1e-5 * max(length(a), max(length(b), length(c)))) return 0.0;
    vec3 ua = normalize(a), ub = normalize(b), uc = normalize(c);
    vec3 enter = vec3(0.0), leave = vec3(0.0);
    float sum = above_unit_edge(a, b, ua, ub, ha, hb, n, enter, leave)
              + above_unit_edge(b, c, ub, uc, hb, hc, n, enter, leave)
              + above_unit_edge(c, a, uc, ua, hc, ha, n, enter, leave);
    if (min(ha, min(hb, hc)) < 0.0) sum += lambert_edge(leave, enter, n);
    return abs(sum) * 0.5;
}

// One edge a→b (unit directions ua, ub) of a convex polygon split by the plane through the receiver (heights ha,
// hb): its terms of Lambert's formula above the plane (x) and below it (y), and where it leaves (`leave`) or enters
// (`enter`) the side above. Two terms whether or not it crosses (the piece on a's side, and the piece past the
// crossing, 0 where there is none: llvmpipe runs both sides of a branch). An edge of length 0 (an octagon that is a
// rectangle) adds nothing.
vec2 split_unit_edge(vec3 a, vec3 b, vec3 ua, vec3 ub, float ha, float hb, vec3 n, inout vec3 enter,
                     inout vec3 leave) {
    bool crosses = (ha >= 0.0) != (hb >= 0.0);
    vec3 cp = crosses ? cut(a, b, ha, hb) : b;
    vec3 uc = crosses ? normalize(cp) : ub;
    float first = unit_lambert_edge(ua, uc, n);
    float second = crosses ? unit_lambert_edge(uc, ub, n) : 0.0;
    if (crosses && ha >= 0.0) leave = cp;
    if (crosses && ha < 0.0) enter = cp;
    return ha >= 0.0 ? vec2(first, second) : vec2(second, first);
}

// triangle_projected_solid_angle for n (x) and −n (y) at once: each edge's Lambert terms taken for the side of the
// plane each of its pieces lies on, closed along the plane where it cuts the triangle (as
// split_octagon_projected_solid_angles). The vertices and cut points are normalised once, and no term is computed
// twice: VCT's injection lights both sides of every surface point, and an emitter cluster's triangles were most of
// its time (llvmpipe runs both sides of a branch, so the two one-sided calls computed ten edge terms; this, seven).
vec2 triangle_projected_solid_angles(vec3 a, vec3 b, vec3 c, vec3 n) {
    float ha = dot(a, n), hb = dot(b, n), hc = dot(c, n);
    float eps = 1e-5 * max(length(a), max(length(b), length(c)));
    bool up = max(ha, max(hb, hc)) > eps, down = min(ha, min(hb, hc)) < -eps;
    vec3 ua = normalize(a), ub = normalize(b), uc = normalize(c);
    vec3 enter = vec3(0.0), leave = vec3(0.0);
    vec2 sum = split_unit_edge(a, b, ua, ub, ha, hb, n, enter, leave) + split_unit_edge(b, c, ub, uc, hb, hc, n, enter,
               leave) + split_unit_edge(c, a, uc, ua, hc, ha, n, enter, leave);
    bool above = ha >= 0.0 || hb >= 0.0 || hc >= 0.0, below = ha < 0.0 || hb < 0.0 || hc < 0.0;
    float closing = above && below ? unit_lambert_edge(normalize(leave), normalize(enter), n) : 0.0;
    return 0.5 * abs(sum + vec2(closing, -closing)) * vec2(up, down);
}

// The projected solid angles, seen from the receiver (the origin) with normal n (x) and with −n (y), of the parts of
// the convex octagon q0…q7 above and below its plane (edges may have length 0: a rectangle is an octagon too). Each
// part is its own edges' pieces closed along the plane, leave → enter above and enter → leave below; Lambert's terms
// for −n are those for n negated, so each edge is walked once for both. No arrays: llvmpipe keeps arrays in memory
// for the whole shader.
vec2 split_octagon_projected_solid_angles(vec3 q0, vec3 q1, vec3 q2, vec3 q3, vec3 q4, vec3 q5, vec3 q6,
                                          vec3 q7, vec3 n) {
    vec4 u = vec4(dot(q0, n), dot(q1, n), dot(q2, n), dot(q3, n));
    vec4 w = vec4(dot(q4, n), dot(q5, n), dot(q6, n), dot(q7, n));
    vec3 u0 = normalize(q0), u1 = normalize(q1), u2 = normalize(q2), u3 = normalize(q3);
    vec3 u4 = normalize(q4), u5 = normalize(q5), u6 = normalize(q6), u7 = normalize(q7);
    vec3 enter = vec3(0.0), leave = vec3(0.0);
    vec2 sum = split_unit_edge(q0, q1, u0, u1, u.x, u.y, n, enter, leave)
             + split_unit_edge(q1, q2, u1, u2, u.y, u.z, n, enter, leave)
             + split_unit_edge(q2, q3, u2, u3, u.z, u.w, n, enter, leave)
             + split_unit_edge(q3, q4, u3, u4, u.w, w.x, n, enter, leave)
             + split_unit_edge(q4, q5, u4, u5, w.x, w.y, n, enter, leave)
             + split_unit_edge(q5, q6, u5, u6, w.y, w.z, n, enter, leave)
             + split_unit_edge(q6, q7, u6, u7, w.z, w.w, n, enter, leave)
             + split_unit_edge(q7, q0, u7, u0, w.w, u.x, n, enter, leave);
    bool above = any(greaterThanEqual(u, vec4(0.0))) || any(greaterThanEqual(w, vec4(0.0)));
    bool below = any(lessThan(u, vec4(0.0))) || any(lessThan(w, vec4(0.0)));
    float closing = above && below ? lambert_edge(leave, enter, n) : 0.0;
    return 0.5 * abs(sum + vec2(closing, -closing));
}
