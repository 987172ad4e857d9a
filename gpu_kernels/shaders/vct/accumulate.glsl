// SPDX-License-Identifier: GPL-3.0-or-later
// Temporal accumulation of the VCT diffuse gather (vct/temporal.py). Frame k (0-based) of a static view turns the
// cone set by another angle; the history holds the running mean of frames 0..k:
//   H_k = H_{k−1} + (C_k − H_{k−1}) / (k + 1)      (H_0 = C_0, so the first frame after a reset is a fresh render)
// An equal-weight mean rather than the exponential blend of Freed 2018, §4.7.2: the jittered frames are samples of one
// integral, not a signal that changes, and any change to the inputs restarts the history (no ghosting).
layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_current;
uniform ivec2 u_image_size;
uniform int u_frame;   // k
layout(rgba32f, binding = 0) uniform image2D u_history;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
    vec4 c = texelFetch(u_current, px, 0);
    vec4 h = u_frame == 0 ? c : imageLoad(u_history, px);
    imageStore(u_history, px, h + (c - h) / float(u_frame + 1));
}
