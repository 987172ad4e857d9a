// VCT radiance injection (seed 004 §4.3, with §4.2's shadow maps): the outgoing diffuse radiance of every occupied
// voxel, lit by every light with the same shadowed evaluation as the Diffuse Direct pass (direct_eval.glsl).
//
// Per direction, not per side of the voxel normal: the voxelizer's normal is a mean of sign-canonicalised normals,
// which says nothing about which side faces a room at an edge or corner voxel (floor + wall average to a diagonal
// pointing into neither). So each of the six faces of the voxel (outward normal ±x, ±y, ±z) gets its own radiance:
//   L_g = albedo · E(p_g, n_g) / π,   p_g = voxel centre + n_g·cell/2 (the face centre), n_g = the face normal,
// i.e. the light a surface in the voxel reflects out through that face; and its coverage
//   α_g = min(1, projected area onto the face's plane / cell²)
// (the opacity of crossing the voxel along that axis). For a directional light the flux through the faces,
// Σ_g α_g·cell²·π·L_g = albedo·A·Σ_i |n_i|·E(±e_i), equals the surface's albedo·A·E(n) whenever n·l is lit on
// every axis it has. Emission is not injected: emissive triangles are lights (light_buffers.py), so E already
// carries their light, and adding it again would count it twice (Cycles' Diffuse Indirect never holds emission).
// Output: rgba32f face images, rgb = L_g (not premultiplied), a = α_g.
//
// The face point lies on the voxel's boundary, but the voxel may hold other surfaces between it and the room it
// faces (at an edge, the +x face centre of a wall voxel can lie just under the floor crossing the same voxel). Those
// are the voxel's own surfaces, not shadows the voxel grid can resolve, so the shadow lookup is moved one voxel
// toward the light (SHADOW_TOWARD_LIGHT): occluders within a voxel of the face are ignored, farther ones shadow as
// for pixels. A face never sees a light behind it (the cosine is ≤ 0 first), so this cannot light the back of a
// wall. Without it the anisotropic white furnace loses 8% of its light to dark edges (32³ grid).
uniform vec3 u_grid_origin;
uniform float u_cell;
#define SHADOW_TOWARD_LIGHT u_cell
#include "lights_common.glsl"
#include "light_eval.glsl"
#include "direct_eval.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
uniform sampler3D u_area;        // voxelize(): rgb projected areas (m²), a total area
uniform sampler3D u_albedo;      // rgb mean diffuse albedo
uniform ivec3 u_grid_size;
uniform int u_light_count;
layout(rgba32f, binding = 0) uniform writeonly image3D u_face[6];   // +x, −x, +y, −y, +z, −z

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 area = texelFetch(u_area, v, 0);
    vec3 albedo = texelFetch(u_albedo, v, 0).rgb;
    vec3 centre = u_grid_origin + (vec3(v) + 0.5) * u_cell;
    float cell2 = u_cell * u_cell;
    for (int g = 0; g < 6; ++g) {
        int axis = g >> 1;
        float alpha = area.a > 0.0 ? min(1.0, area[axis] / cell2) : 0.0;
        vec3 radiance = vec3(0.0);
        if (alpha > 0.0 && max(albedo.r, max(albedo.g, albedo.b)) > 0.0) {
            vec3 n = vec3(0.0);
            n[axis] = (g & 1) == 0 ? 1.0 : -1.0;
            vec3 p = centre + n * (0.5 * u_cell);
            vec3 e = vec3(0.0);
            for (int i = 0; i < u_light_count; ++i) e += light_irradiance(lights[i], p, n, n);
            radiance = albedo * e / PI;
        }
        imageStore(u_face[g], v, vec4(radiance, alpha));
    }
}
