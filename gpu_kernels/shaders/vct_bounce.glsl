// VCT multiple bounces (seed 004 traces cones from pixels only; gathering at the voxels too is the same estimator
// applied to the voxel faces): each occupied voxel face g gathers the irradiance E_g arriving over the hemisphere
// of its outward normal from the current radiance volumes (vct_common.glsl), and its outgoing radiance becomes
//   L_g = L_direct,g + albedo · E_g / π
// (Jacobi iteration: after k passes the volumes hold light reflected up to k + 1 times). The face point and its
// tangent plane are the face centre, the farthest a surface inside the voxel can lie along that normal, so the
// cone's self-occlusion bound (trace_cone) holds for whatever the voxel holds.
#include "vct_common.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
uniform sampler3D u_direct[6];   // vct_inject faces: rgb = L_direct, a = α_g
uniform sampler3D u_albedo;
layout(rgba32f, binding = 0) uniform writeonly image3D u_face[6];

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec3 albedo = texelFetch(u_albedo, v, 0).rgb;
    bool reflects = max(albedo.r, max(albedo.g, albedo.b)) > 0.0;
    vec3 centre = u_grid_origin + (vec3(v) + 0.5) * u_cell;
    for (int g = 0; g < 6; ++g) {
        vec4 direct = texelFetch(u_direct[g], v, 0);
        vec3 radiance = direct.rgb;
        if (direct.a > 0.0 && reflects) {
            vec3 n = vec3(0.0);
            n[g >> 1] = (g & 1) == 0 ? 1.0 : -1.0;
            vec4 e = gather_irradiance(centre + n * (0.5 * u_cell), n, n);
            radiance += albedo * e.rgb / VCT_PI;
        }
        imageStore(u_face[g], v, vec4(radiance, direct.a));
    }
}
