// SPDX-License-Identifier: GPL-3.0-or-later
// Vertex stage shared by the programs that rasterise the scene's surfaces with their materials (G-buffer, RSMs):
// world position, shading normal, UV and geometric normal pass through; one view-projection matrix.
#pragma once
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec3 in_geo_normal;
uniform mat4 u_view_projection;
#if defined(VERTEX_MATERIAL)
layout(location = 4) in float in_material;   // the triangle's material index (direct/geometry.SURFACE_MATERIAL)
flat out float v_material;
#endif
out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
out vec3 v_geo_normal;
void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_uv = in_uv;
    v_geo_normal = in_geo_normal;
#if defined(VERTEX_MATERIAL)
    v_material = in_material;
#endif
    gl_Position = u_view_projection * vec4(in_position, 1.0);
}
