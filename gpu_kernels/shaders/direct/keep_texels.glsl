// SPDX-License-Identifier: GPL-3.0-or-later
// The depths inside some rectangles of the shadow atlas, copied before an object's move draws over them
// (direct/shadows.keep_texels), rectangle after rectangle, each row by row. MODE_CHANGED, after the draws: per
// rectangle the box of the texels whose depth the draws changed (x0, y0, x1, y1; x1 ≤ x0: none). One invocation
// per texel of them all (a dispatch per rectangle's box would run the largest's size for every one of them).
layout(local_size_x = 64) in;
uniform sampler2D u_depth;   // the atlas's depths, nearest, without comparison
uniform int u_rects;
uniform int u_total;         // texels in all the rectangles
layout(std430, binding = 0) readonly buffer Rects { ivec4 rects[]; };   // per rectangle: (x, y, w, h), (first, …)
#if defined(MODE_CHANGED)
layout(std430, binding = 1) readonly buffer Texels { float texels[]; };
layout(std430, binding = 2) buffer Changed { int changed[]; };   // 4 per rectangle, starting (big, big, -1, -1)
#else
layout(std430, binding = 1) writeonly buffer Texels { float texels[]; };
#endif

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_total) return;
    int lo = 0, hi = u_rects - 1;   // the last rectangle starting at or before texel i
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (rects[2 * mid + 1].x <= i) lo = mid; else hi = mid - 1;
    }
    ivec4 r = rects[2 * lo];
    int local = i - rects[2 * lo + 1].x;
    ivec2 t = r.xy + ivec2(local % r.z, local / r.z);
    float depth = texelFetch(u_depth, t, 0).r;
#if defined(MODE_CHANGED)
    if (texels[i] == depth) return;
    atomicMin(changed[4 * lo], t.x);
    atomicMin(changed[4 * lo + 1], t.y);
    atomicMax(changed[4 * lo + 2], t.x + 1);
    atomicMax(changed[4 * lo + 3], t.y + 1);
#else
    texels[i] = depth;
#endif
}
