// SPDX-License-Identifier: GPL-3.0-or-later
// VCT multiple bounces (Freed 2018 traces cones from pixels only; gathering at the voxels too is the same estimator
// applied to the voxel faces): each occupied voxel face g gathers the irradiance E_g arriving over the hemisphere
// of its outward normal from the current radiance volumes (vct/common.glsl), and its outgoing radiance becomes
//   L_g = L_direct,g + albedo · E_g / π
// (Jacobi iteration: after k passes the volumes hold light reflected up to k + 1 times). The cones start from the
// face's surface centroid (vct/inject.glsl: the mean of the surface points whose light leaves through that face),
// so an edge voxel's wall face gathers from the wall inside the room, not from under the floor crossing its
// centre; the tangent plane is the face's (axis) normal through that point. A face without raster samples uses
// its face centre.
#include "vct/common.glsl"
#include "vct/arrays.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_direct[6];   // vct_inject faces: rgb = L_direct, a = α_g
uniform sampler3D u_albedo;
layout(rgba32f, binding = 0) uniform writeonly image3D u_face[6];
VCT_FETCH6(direct_face, u_direct)
VCT_STORE6(store_face, u_face)

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 direct[6];
    float coverage = 0.0;
    for (int g = 0; g < 6; ++g) {
        direct[g] = direct_face(g, v, 0);
        coverage = max(coverage, direct[g].a);
    }
    if (coverage <= 0.0) return;   // an empty voxel (the face images start zeroed, vct._texture3d)
    vec3 albedo = texelFetch(u_albedo, v, 0).rgb;
    bool reflects = max(albedo.r, max(albedo.g, albedo.b)) > 0.0;
    for (int g = 0; g < 6; ++g) {
        vec3 radiance = direct[g].rgb;
        if (direct[g].a > 0.0 && reflects) {
            vec3 n = vec3(0.0);
            n[g >> 1] = (g & 1) == 0 ? 1.0 : -1.0;
            vec4 e = gather_irradiance(centroid_face(g, v, 0).xyz, n, n, vec2(1.0, 0.0));
            radiance += albedo * e.rgb / VCT_PI;
        }
        store_face(g, v, vec4(radiance, direct[g].a));
    }
}
