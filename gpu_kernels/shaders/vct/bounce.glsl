// SPDX-License-Identifier: GPL-3.0-or-later
// VCT multiple bounces (Freed 2018 traces cones from pixels only; gathering at the voxels too is the same estimator
// applied to the voxel faces): each occupied voxel face g gathers the irradiance E_g arriving over the hemisphere
// of its outward normal from the current radiance volumes (vct/common.glsl), and its outgoing radiance becomes
//   L_g = L_direct,g + albedo_g · E_g / π   (albedo_g the face's, vct/face_albedo.glsl)
// (Jacobi iteration: after k passes the volumes hold light reflected up to k + 1 times). The cones start from the
// face's surface centroid (vct/inject.glsl: the mean of the surface points whose light leaves through that face),
// so an edge voxel's wall face gathers from the wall inside the room, not from under the floor crossing its
// centre; the tangent plane is the face's (axis) normal through that point. A face without raster samples uses
// its face centre.
// The faces are gathered from a list of those with coverage (MODE_LIST makes it once per injection), one face per
// invocation: over the grid, a SIMD group of voxels along a wall's normal had one lane with a face and seven idle
// for all its cones, and a floor voxel beside a wall voxel ran both faces' cones in every lane.
#include "vct/common.glsl"
#include "vct/arrays.glsl"

uniform sampler3D u_direct[6];   // vct_inject faces: rgb = L_direct, a = α_g
VCT_FETCH6(direct_face, u_direct)

#if defined(MODE_LIST)
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
layout(std430, binding = 3) buffer Count { uint face_count; };    // gl/bind.dispatch_counted
layout(std430, binding = 5) writeonly buffer FaceList { ivec4 faces[]; };   // voxel, face g
uniform uint u_capacity;   // faces the list holds: the count goes on past it (vct/bounce.face_list makes it larger)

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    for (int g = 0; g < 6; ++g) {
        if (direct_face(g, v, 0).a <= 0.0) continue;
        uint i = atomicAdd(face_count, 1u);
        if (i < u_capacity) faces[i] = ivec4(v, g);
    }
}
#else
// MODE_RECORD_GATHER: the gathers, keeping each face's steps that absorbed light (vct/hits.glsl, header per list
// entry); MODE_REPLAY_GATHER: the same gathers from those steps and the current volumes, bit for bit (the steps
// depend on the opacities alone, which the bounces share), a face the record could not keep gathered again.
layout(local_size_x = 64) in;
layout(std430, binding = 5) readonly buffer FaceList { ivec4 faces[]; };
uniform int u_face_first;   // this dispatch's first face (at most 65535 groups a dispatch)
uniform int u_face_count;   // faces in the list
uniform sampler3D u_albedo[6];   // vct/face_albedo.glsl: each face's albedo
VCT_FETCH6(face_albedo, u_albedo)
layout(rgba32f, binding = 0) uniform writeonly image3D u_face[6];
VCT_STORE6(store_face, u_face)

#if defined(MODE_REPLAY_GATHER)
// E at the face as gather_irradiance and trace_cone sum it, step by step in their order (cone_step's arithmetic).
vec3 gather_replay(uvec4 header) {
    vec3 e = vec3(0.0), radiance = vec3(0.0);
    int cone = 0;
    uint chunk = header.x;
    for (uint h = 0u; h < header.y; ++h) {
        GatherStep st = gather_steps[hit_at(h, chunk)];
        uint tag = floatBitsToUint(st.alpha_t_tag.z);
        end_cones(e, radiance, cone, int(tag & 31u));
        uint sides = tag >> 5;
        // Each axis's volume picked from its two by name, not through volume_at's six-way switch: llvmpipe runs
        // every case of a switch its lanes disagree on, so that read six textures for each one used (measured:
        // the replays took twice as long).
        vec3 q = st.uvw_lod.xyz;
        float lod = st.uvw_lod.w;
        vec4 sx = (sides & 1u) == 0u ? textureLod(u_replay0, q, lod) : textureLod(u_replay1, q, lod);
        vec4 sy = (sides & 2u) == 0u ? textureLod(u_replay2, q, lod) : textureLod(u_replay3, q, lod);
        vec4 sz = (sides & 4u) == 0u ? textureLod(u_replay4, q, lod) : textureLod(u_replay5, q, lod);
        vec3 w = st.w_tau.xyz;
        float tau = st.w_tau.w;
        vec3 step_radiance = (w.x * sx.rgb + w.y * sy.rgb + w.z * sz.rgb) / tau;
        float alpha = st.alpha_t_tag.x;
        vec4 s = vec4(alpha * step_radiance, alpha);
        radiance += st.alpha_t_tag.y * s.rgb;
    }
    end_cones(e, radiance, cone, u_cone_count);
    return e;
}
#endif

vec3 face_irradiance(int i, ivec3 v, int g) {
    vec3 n = vec3(0.0);
    n[g >> 1] = (g & 1) == 0 ? 1.0 : -1.0;
#if defined(MODE_REPLAY_GATHER)
    uvec4 header = hit_headers[i];
    if (header.w == HIT_RECORDED) return gather_replay(header);
#endif
    vec3 e = gather_irradiance(centroid_face(g, v, 0).xyz, n, n, vec2(1.0, 0.0)).rgb;
#if defined(MODE_RECORD_GATHER)
    hit_headers[i] = uvec4(g_first, g_hits, 0u, g_overflow ? 0u : HIT_RECORDED);
#endif
    return e;
}

void main() {   // the faces without coverage keep the zeros their images start with (vct._texture3d)
    int i = u_face_first + int(gl_GlobalInvocationID.x);
    if (i >= u_face_count) return;
    ivec3 v = faces[i].xyz;
    int g = faces[i].w;
    vec4 direct = direct_face(g, v, 0);
    vec3 albedo = face_albedo(g, v, 0).rgb;
    vec3 radiance = direct.rgb;
    if (max(albedo.r, max(albedo.g, albedo.b)) > 0.0) radiance += albedo * face_irradiance(i, v, g) / VCT_PI;
    store_face(g, v, vec4(radiance, direct.a));
}
#endif
