// SPDX-License-Identifier: GPL-3.0-or-later
// Reflective shadow map (Dachsbacher and Stamminger 2005; Elvek 2012, §3.1): from one shadow view of a light, store the
// surfels the light sees — world position (w = view index + 1), normal facing the light (w = μ = n·l), and what the
// injection needs to compute their albedo (lpv/inject.glsl texel_albedo): the texture's colour where the material
// has one (else 1) and the material's index. Not the albedo itself: the RSM then holds no material colour, so a
// colour edit redraws no view, and the injection re-bins only the light the edited material's texels reflect.
// The material index comes with each vertex, so one draw spans every material without a texture
// (direct/geometry.material_batches); a textured one is drawn alone, with its texture bound.
#define VERTEX_MATERIAL
#if defined(VERTEX_SHADER)
#include "common/surface_vertex.glsl"
#endif

#if defined(FRAGMENT_SHADER)
#include "common/materials.glsl"
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec3 v_geo_normal;
flat in float v_material;
uniform vec3 u_origin;       // the view's eye (perspective)
uniform vec3 u_forward;      // the view's axis (orthographic: the sun's direction)
uniform bool u_ortho;
uniform float u_view_index;
// > 0 (perspective): the depth test compares radial distance / u_far, linear like the shadow maps' own
// (direct/shadow_depth.glsl); the projective depth's steps at a few metres (near = far / 10⁴) are a millimetre,
// and a rug lying 1 mm over a floor z-fought with it, the floor's colour showing through in patches.
uniform float u_far;
layout(location = 0) out vec4 out_position;  // xyz world position, w = view index + 1 (0: empty texel)
layout(location = 1) out vec4 out_normal;    // xyz shading normal facing the light, w = μ = n·l
layout(location = 2) out vec4 out_albedo;    // rgb the base colour texture's colour (1: none), w = material index

void main() {
    vec3 to_light = u_ortho ? -u_forward : normalize(u_origin - v_position);
    vec3 geo_n = normalize(v_geo_normal);
    vec3 n = normalize(v_normal);
    if (dot(geo_n, to_light) < 0.0) {  // two-sided: the side the light sees reflects
        n = -n;
    }
    gl_FragDepth = u_far > 0.0 ? length(v_position - u_origin) / u_far : gl_FragCoord.z;
    out_position = vec4(v_position, u_view_index + 1.0);
    out_normal = vec4(n, max(dot(n, to_light), 0.0));
    out_albedo = vec4(u_use_texture ? texture(u_base_texture, v_uv).rgb : vec3(1.0), v_material);
}
#endif
