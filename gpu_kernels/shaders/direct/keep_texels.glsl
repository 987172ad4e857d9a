// SPDX-License-Identifier: GPL-3.0-or-later
// The depths inside some rectangles of the shadow atlas, copied before an object's move draws over them
// (direct/shadows.keep_texels): one rectangle per z, row by row from its first index.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler2D u_depth;   // the atlas's depths, nearest, without comparison
layout(std430, binding = 0) readonly buffer Rects { ivec4 rects[]; };   // per rectangle: (x, y, w, h), (first, …)
layout(std430, binding = 1) writeonly buffer Texels { float texels[]; };

void main() {
    ivec3 id = ivec3(gl_GlobalInvocationID);
    ivec4 r = rects[2 * id.z];
    if (id.x >= r.z || id.y >= r.w) return;
    texels[rects[2 * id.z + 1].x + id.y * r.z + id.x] = texelFetch(u_depth, r.xy + id.xy, 0).r;
}
