// SPDX-License-Identifier: GPL-3.0-or-later
// The sky's diffuse share (direct/light.glsl MODE_SKY) averaged along one image axis over each pixel's penumbra, on
// its own surface only. Each sky direction stands for a cone of half-width h = √(4π/K)/2 whose shadow edge fades
// over h × the blocker's distance on the receiver; the cells an edge crosses are already tested over their cones
// (direct/sky.glsl sky_soften), and a box of that half-width around the pixel, on the receiver's plane, smooths
// what is left of their steps (as percentage-closer soft shadows widen a filter by the blocker's distance: Fernando
// 2005, "Percentage-closer soft shadows"). The glossy share is left as tested: a glossy reflection of a window is
// as sharp as the lobe, and averaging it over the penumbra blurred it. Filtering over the visible surface rather
// than in each direction's shadow map keeps the light from leaking through a thin wall beside the receiver: only
// pixels on the receiver's own plane (position and normal: a bilateral filter, Tomasi and Manduchi 1998) are
// averaged. Run once per axis.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_out;
uniform sampler2D u_shares;     // x, y: the shares; z: the penumbra's half-width (m); w unused
uniform sampler2D u_position;   // xyz world position, w hit flag
uniform sampler2D u_geo_normal; // xyz geometric normal
uniform ivec2 u_size;
uniform ivec2 u_axis;           // (1, 0) or (0, 1)

#define MAX_TAPS 12          // per side: at most 25 reads per pixel and axis, spread over the penumbra
#define MAX_RADIUS_PX 96.0   // the penumbra's half-width in pixels at most
#define SAME_NORMAL 0.9      // a neighbour this aligned with the pixel's normal ...
#define PLANE_SLACK 0.05     // ... and this near its plane (× the half-width) is on the same surface

bool on_surface(ivec2 q, vec3 p, vec3 n, float slack, out vec4 pq) {
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, u_size))) return false;
    pq = texelFetch(u_position, q, 0);
    if (pq.w < 0.5) return false;
    vec3 nq = texelFetch(u_geo_normal, q, 0).xyz;
    return dot(normalize(nq), n) >= SAME_NORMAL && abs(dot(pq.xyz - p, n)) <= slack;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_size))) return;
    vec4 centre = texelFetch(u_shares, px, 0);
    vec4 pos = texelFetch(u_position, px, 0);
    float half_width = centre.z;
    if (pos.w < 0.5 || half_width <= 0.0) {
        imageStore(u_out, px, centre);
        return;
    }
    vec3 p = pos.xyz;
    vec3 n = normalize(texelFetch(u_geo_normal, px, 0).xyz);
    // A pixel's footprint along the axis (m), from a neighbour on the same surface.
    float footprint = 0.0;
    vec4 pq;
    for (int s = -1; s <= 1; s += 2)
        if (on_surface(px + s * u_axis, p, n, 1e30, pq)) {
            float f = length(pq.xyz - p);
            footprint = footprint > 0.0 ? min(footprint, f) : f;
        }
    float radius = footprint > 0.0 ? min(half_width / footprint, MAX_RADIUS_PX) : 0.0;
    if (radius < 1.0) {
        imageStore(u_out, px, centre);
        return;
    }
    // Every pixel within the radius (no pixel read twice), or MAX_TAPS spread evenly over a wider one.
    bool dense = radius <= float(MAX_TAPS);
    int taps = dense ? int(floor(radius + 1e-3)) : MAX_TAPS;
    float stride = dense ? 1.0 : radius / float(MAX_TAPS);
    float slack = PLANE_SLACK * half_width + 2.0 * footprint;
    float sum = centre.x;
    float count = 1.0;
    for (int i = -taps; i <= taps; ++i) {
        if (i == 0) continue;
        ivec2 q = px + u_axis * int(round(float(i) * stride));
        if (!on_surface(q, p, n, slack, pq) || length(pq.xyz - p) > 1.5 * half_width) continue;
        sum += texelFetch(u_shares, q, 0).x;
        count += 1.0;
    }
    imageStore(u_out, px, vec4(sum / count, centre.y, half_width, 0.0));
}
