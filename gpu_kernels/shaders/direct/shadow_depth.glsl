// SPDX-License-Identifier: GPL-3.0-or-later
// Depth-only pass for one shadow view (a tile of the shadow atlas). Both faces are drawn: surfaces are two-sided.
// Perspective views store radial distance / far instead of the hyperbolic z: 24-bit depth then resolves
// far·2⁻²⁴ everywhere, where hyperbolic depth with near = far·10⁻⁴ would lose most of its bits near the far plane.
#if defined(VERTEX_SHADER)
layout(location = 0) in vec3 in_position;
uniform mat4 u_view_projection;
out vec3 v_world;
void main() {
    v_world = in_position;
    gl_Position = u_view_projection * vec4(in_position, 1.0);
}
#endif

#if defined(FRAGMENT_SHADER)
in vec3 v_world;
uniform vec3 u_origin;
uniform float u_far;       // 0 for orthographic views: keep the rasterised depth
void main() {
    gl_FragDepth = u_far > 0.0 ? length(v_world - u_origin) / u_far : gl_FragCoord.z;
}
#endif
