// SPDX-License-Identifier: GPL-3.0-or-later
// Reflective shadow map (Dachsbacher and Stamminger 2005; Elvek 2012, §3.1): from one shadow view of a light, store the
// surfels the light sees — world position (w = view index + 1), normal facing the light, albedo. The injection pass
// turns each texel into a VPL whose flux it derives from these and the light's units. The albedo is what the surface
// reflects of light from the light's direction: the diffuse base's share and the glossy layers' directional albedo
// (Cycles' Diffuse and Glossy Color at μ = n·l, by reciprocity); a VPL has no lobe, so the glossy part leaves
// diffusely, as in the voxels (voxel/common.glsl voxel_albedo).
#if defined(VERTEX_SHADER)
#include "common/surface_vertex.glsl"
#endif

#if defined(FRAGMENT_SHADER)
#include "common/materials.glsl"
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec3 v_geo_normal;
uniform vec3 u_origin;       // the view's eye (perspective)
uniform vec3 u_forward;      // the view's axis (orthographic: the sun's direction)
uniform bool u_ortho;
uniform float u_view_index;
// > 0 (perspective): the depth test compares radial distance / u_far, linear like the shadow maps' own
// (direct/shadow_depth.glsl); the projective depth's steps at a few metres (near = far / 10⁴) are a millimetre,
// and a rug lying 1 mm over a floor z-fought with it, the floor's colour showing through in patches.
uniform float u_far;
layout(location = 0) out vec4 out_position;  // xyz world position, w = view index + 1 (0: empty texel)
layout(location = 1) out vec4 out_normal;    // xyz shading normal facing the light
layout(location = 2) out vec4 out_albedo;    // rgb albedo (diffuse + glossy)

void main() {
    vec3 to_light = u_ortho ? -u_forward : normalize(u_origin - v_position);
    vec3 geo_n = normalize(v_geo_normal);
    vec3 n = normalize(v_normal);
    if (dot(geo_n, to_light) < 0.0) {  // two-sided: the side the light sees reflects
        n = -n;
    }
    gl_FragDepth = u_far > 0.0 ? length(v_position - u_origin) / u_far : gl_FragCoord.z;
    out_position = vec4(v_position, u_view_index + 1.0);
    out_normal = vec4(n, 0.0);
    float mu = max(dot(n, to_light), 0.0);
    out_albedo = vec4(diffuse_albedo(v_uv, mu) + glossy_albedo(v_uv, mu), 0.0);
}
#endif
