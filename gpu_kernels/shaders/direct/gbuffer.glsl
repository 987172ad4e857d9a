// SPDX-License-Identifier: GPL-3.0-or-later
// G-buffer from the scene camera: world position, shading normal, diffuse colour, emission, geometric normal, glossy
// colour and roughness (the VCT specular cone, vct/specular.glsl), and the glossy lobe's Fresnel (Glossy Direct).
// Sampled at pixel centres with no MSAA, like Cycles with a ~0.01 px pixel filter (docs/conventions.md).
#if defined(VERTEX_SHADER)
#include "common/surface_vertex.glsl"
#endif

#if defined(FRAGMENT_SHADER)
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec3 v_geo_normal;
uniform vec3 u_camera_position;
uniform vec3 u_camera_forward;   // unit view axis, for planar depth (Cycles' Depth pass)
uniform bool u_camera_ortho;
#include "common/materials.glsl"

layout(location = 0) out vec4 out_position;      // xyz world position, w = 1 where geometry was hit
layout(location = 1) out vec4 out_normal;        // xyz shading normal facing the viewer, w = planar depth
layout(location = 2) out vec4 out_albedo;        // rgb Diffuse Color, w = 1
layout(location = 3) out vec4 out_emission;      // rgb emitted radiance (emission colour × strength)
layout(location = 4) out vec4 out_geo_normal;    // xyz geometric normal facing the viewer
layout(location = 5) out vec4 out_glossy;        // rgb Glossy Color, w = Principled roughness
layout(location = 6) out vec4 out_specular;      // rgb base colour, w = material index (Glossy Direct's Fresnel)

void main() {
    vec3 view_dir = u_camera_ortho ? -u_camera_forward : normalize(u_camera_position - v_position);
    vec3 geo_n = normalize(v_geo_normal);
    vec3 n = normalize(v_normal);
    // Surfaces are two-sided as in Cycles: seen from behind, both normals flip toward the viewer.
    if (dot(geo_n, view_dir) < 0.0) {
        geo_n = -geo_n;
        n = -n;
    }
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(n, dot(v_position - u_camera_position, u_camera_forward));
    out_albedo = vec4(diffuse_albedo(v_uv, dot(n, view_dir)), 1.0);
    out_emission = vec4(u_emission, 1.0);
    float mu = dot(n, view_dir);
    out_geo_normal = vec4(geo_n, 0.0);
    out_glossy = vec4(glossy_albedo(v_uv, mu), u_roughness);
    out_specular = glossy_inputs(v_uv);
}
#endif
