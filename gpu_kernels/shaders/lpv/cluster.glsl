// SPDX-License-Identifier: GPL-3.0-or-later
// The next bounce's VPLs for the gathered transport (LpvSettings.transport = "gather"): every surface voxel reflects
// the light it received in the last pass, Φ = albedo × E × area per side (as lpv/bounce.glsl injects it), and the
// voxels of one S×S×S block are clustered into at most three VPLs, so that a gather costs a few hundred VPLs rather
// than one per voxel. A block's sides are split by plane (the first lit side's plane, the first side off it, the
// rest) so that a block holding a floor and a wall gives a VPL on each instead of one floating between them.
// Each VPL sits at the flux-weighted mean of its voxels' centres, with their mean normal and their total area
// (normal.w), which the gather uses as the source's extent (lpv/gather.glsl).
#include "lpv/common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
#include "common/structs.glsl"
layout(std430, binding = 6) writeonly buffer VplList { Vpl vpls[]; };
uniform sampler3D u_front;          // last pass: irradiance of each fine voxel's front / back side
uniform sampler3D u_back;
uniform sampler3D u_voxel_normal;
uniform sampler3D u_voxel_area;
uniform sampler3D u_voxel_albedo;        // the front side's albedo (voxel/voxelize.py sides=True)
uniform sampler3D u_voxel_albedo_back;   // the back side's
uniform vec3 u_fine_origin;
uniform ivec3 u_fine_size;
uniform float u_voxel;              // fine voxel size (m)
uniform int u_block;                // S: fine voxels per block side
uniform ivec3 u_blocks;

void main() {
    ivec3 b = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(b, u_blocks))) return;
    vec3 flux[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    vec3 position[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    vec3 normal[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    float weight[3] = float[3](0.0, 0.0, 0.0);
    float area[3] = float[3](0.0, 0.0, 0.0);
    vec3 plane_p[2] = vec3[2](vec3(0.0), vec3(0.0));
    vec3 plane_n[2] = vec3[2](vec3(0.0), vec3(0.0));
    int planes = 0;
    for (int z = 0; z < u_block; ++z)
        for (int y = 0; y < u_block; ++y)
            for (int x = 0; x < u_block; ++x) {
                ivec3 f = b * u_block + ivec3(x, y, z);
                if (any(greaterThanEqual(f, u_fine_size))) continue;
                vec4 a = texelFetch(u_voxel_area, f, 0);
                vec3 nv = texelFetch(u_voxel_normal, f, 0).xyz;
                if (a.a <= 0.0 || dot(nv, nv) == 0.0) continue;
                nv = normalize(nv);
                vec3 p = u_fine_origin + (vec3(f) + 0.5) * u_voxel;
                for (int side = 0; side < 2; ++side) {
                    vec3 n = side == 0 ? nv : -nv;
                    vec3 e = (side == 0 ? texelFetch(u_front, f, 0) : texelFetch(u_back, f, 0)).rgb;
                    vec3 albedo = (side == 0 ? texelFetch(u_voxel_albedo, f, 0) : texelFetch(u_voxel_albedo_back, f, 0)).rgb;
                    vec3 phi = albedo * e * a.a;
                    float w = dot(phi, vec3(0.2126, 0.7152, 0.0722));  // Rec.709 luminance
                    if (w <= 0.0) continue;
                    int slot = 2;
                    for (int k = 0; k < planes; ++k)
                        if (dot(n, plane_n[k]) > 0.9 && abs(dot(p - plane_p[k], plane_n[k])) < u_voxel) {
                            slot = k;
                            break;
                        }
                    if (slot == 2 && planes < 2) {
                        slot = planes;
                        plane_p[planes] = p;
                        plane_n[planes] = n;
                        ++planes;
                    }
                    flux[slot] += phi;
                    position[slot] += w * p;
                    normal[slot] += w * n;
                    weight[slot] += w;
                    area[slot] += a.a;
                }
            }
    int index = (b.z * u_blocks.y + b.y) * u_blocks.x + b.x;
    for (int s = 0; s < 3; ++s) {
        if (weight[s] <= 0.0 || dot(normal[s], normal[s]) == 0.0) continue;
        vpls[3 * index + s] = Vpl(vec4(position[s] / weight[s], 1.0), vec4(normalize(normal[s]), area[s]),
                                  vec4(flux[s], 0.0));
    }
}
