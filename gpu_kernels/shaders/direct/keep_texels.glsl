// SPDX-License-Identifier: GPL-3.0-or-later
// The depths inside some rectangles of the shadow atlas, copied before an object's move draws over them
// (direct/shadows.keep_texels): one rectangle per z, row by row from its first index. MODE_CHANGED, after the
// draws: per rectangle the box of the texels whose depth the draws changed (x0, y0, x1, y1; x1 ≤ x0: none).
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler2D u_depth;   // the atlas's depths, nearest, without comparison
layout(std430, binding = 0) readonly buffer Rects { ivec4 rects[]; };   // per rectangle: (x, y, w, h), (first, …)
#if defined(MODE_CHANGED)
layout(std430, binding = 1) readonly buffer Texels { float texels[]; };
layout(std430, binding = 2) buffer Changed { int changed[]; };   // 4 per rectangle, starting (big, big, -1, -1)
#else
layout(std430, binding = 1) writeonly buffer Texels { float texels[]; };
#endif

void main() {
    ivec3 id = ivec3(gl_GlobalInvocationID);
    ivec4 r = rects[2 * id.z];
    if (id.x >= r.z || id.y >= r.w) return;
    int i = rects[2 * id.z + 1].x + id.y * r.z + id.x;
    float depth = texelFetch(u_depth, r.xy + id.xy, 0).r;
#if defined(MODE_CHANGED)
    if (texels[i] == depth) return;
    ivec2 t = r.xy + id.xy;
    atomicMin(changed[4 * id.z], t.x);
    atomicMin(changed[4 * id.z + 1], t.y);
    atomicMax(changed[4 * id.z + 2], t.x + 1);
    atomicMax(changed[4 * id.z + 3], t.y + 1);
#else
    texels[i] = depth;
#endif
}
