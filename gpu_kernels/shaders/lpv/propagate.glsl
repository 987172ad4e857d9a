// SPDX-License-Identifier: GPL-3.0-or-later
// One LPV propagation step, gathering (Kaplanyan and Dachsbacher 2010; Elvek 2012, §3.3.1; Kaplanyan 2009, §N.5).
// Each cell receives light from its six neighbours. From a neighbour, light reaches the five faces of this cell
// that do not touch it: the far face subtends 0.4006696846 sr from the neighbour's centre and each side face
// 0.4234313544 sr (far + 4·side = 2π/3, so six neighbours share exactly 4π — flux is conserved). The flux through a
// face, Φ = I(ω_face)·Δω, is re-emitted from this cell's centre as a clamped cosine lobe toward that face,
// (Φ/π)·lobe, whose flux is again Φ. Fuzzy occlusion (Elvek 2012, §3.4) scales the light crossing the shared face by
// the fraction of that face left open by the geometry volume. The result goes to u_dst and is added to u_accum.
// It also accumulates, per cell and per direction of travel, the flux incident on the face it shares with that
// neighbour (before blocking): every face crossing is counted once, and light stopped at a face is counted exactly
// once there — the flux its surfaces absorb (see lpv/lighting.glsl, MODE_FLUX).
#include "lpv/common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_src_r;
uniform sampler3D u_src_g;
uniform sampler3D u_src_b;
uniform sampler3D u_geometry;   // blocked fraction of each cell's lower faces (x, y, z), one cell larger
uniform bool u_occlusion;
uniform bool u_clamp_negative;  // clamp negative face fluxes (adds energy; measured in tests) — off by default
uniform ivec3 u_grid_size;
uniform float u_flux_scale;     // fixed-point scale for the flux-moved counter
// Unclamped propagation is linear: from the neighbour along AXES[n], the re-projected coefficients are
// u_transfer[n] · c and the flux incident on the shared face is dot(u_incident[n], c) — the same five-face sums
// as the loop below, precomputed on the CPU (lpv.transfer_matrices).
uniform mat4 u_transfer[6];
uniform vec4 u_incident[6];
layout(rgba32f, binding = 0) uniform writeonly image3D u_dst_r;
layout(rgba32f, binding = 1) uniform writeonly image3D u_dst_g;
layout(rgba32f, binding = 2) uniform writeonly image3D u_dst_b;
layout(rgba32f, binding = 3) uniform image3D u_accum_r;
layout(rgba32f, binding = 4) uniform image3D u_accum_g;
layout(rgba32f, binding = 5) uniform image3D u_accum_b;
layout(std430, binding = 5) buffer FluxCounter { int moved; };
layout(std430, binding = 6) buffer FaceFlux { vec4 face_flux[]; };  // 6 per cell: rgb flux entering along AXES[n]

const float FAR_FACE = 0.4006696846;
const float SIDE_FACE = 0.4234313544;
const float PI = 3.14159265358979;
const ivec3 AXES[6] = ivec3[](ivec3(1, 0, 0), ivec3(-1, 0, 0), ivec3(0, 1, 0), ivec3(0, -1, 0), ivec3(0, 0, 1),
                              ivec3(0, 0, -1));

// Open fraction of the face between cell c and its neighbour c − d: the blocking texture holds, at cell k, the
// blocked fraction of k's lower face normal to each axis (lpv.face_blocking).
float face_transmittance(ivec3 c, ivec3 d) {
    if (!u_occlusion) return 1.0;
    int axis = d.x != 0 ? 0 : (d.y != 0 ? 1 : 2);
    ivec3 k = c + max(-d, ivec3(0));  // along −a the shared face is the lower face of c + e_a
    return 1.0 - texelFetch(u_geometry, k, 0)[axis];
}

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, u_grid_size))) return;
    vec4 r = vec4(0.0), g = vec4(0.0), b = vec4(0.0);
    int cell_index = (c.z * u_grid_size.y + c.y) * u_grid_size.x + c.x;
    for (int n = 0; n < 6; ++n) {
        ivec3 d = AXES[n];              // light travels along d, from the neighbour c − d into this cell
        ivec3 src = c - d;
        if (any(lessThan(src, ivec3(0))) || any(greaterThanEqual(src, u_grid_size))) continue;  // open border
        float open = face_transmittance(c, d);
        vec4 cr = texelFetch(u_src_r, src, 0), cg = texelFetch(u_src_g, src, 0), cb = texelFetch(u_src_b, src, 0);
        if (!u_clamp_negative) {
            vec3 incident = vec3(dot(u_incident[n], cr), dot(u_incident[n], cg), dot(u_incident[n], cb));
            face_flux[cell_index * 6 + n] += vec4(incident, 0.0);
            r += open * (u_transfer[n] * cr);
            g += open * (u_transfer[n] * cg);
            b += open * (u_transfer[n] * cb);
            continue;
        }
        vec3 dir = vec3(d);
        vec3 incident = vec3(0.0);
        for (int f = 0; f < 6; ++f) {
            vec3 face = vec3(AXES[f]);
            if (dot(face, dir) < -0.5) continue;  // the face shared with the neighbour
            bool far_face = dot(face, dir) > 0.5;
            // From the neighbour's centre (at −d) to this face's centre (at face/2).
            vec3 w = far_face ? dir : normalize(dir + 0.5 * face);
            float solid_angle = far_face ? FAR_FACE : SIDE_FACE;
            vec4 y = sh_basis(w);
            vec3 flux = vec3(dot(cr, y), dot(cg, y), dot(cb, y)) * solid_angle;
            if (u_clamp_negative) flux = max(flux, vec3(0.0));
            incident += flux;
            flux *= open;
            vec4 lobe = sh_clamped_cosine(face) / PI;
            r += flux.r * lobe;
            g += flux.g * lobe;
            b += flux.b * lobe;
        }
        face_flux[cell_index * 6 + n] += vec4(incident, 0.0);
    }
    imageStore(u_dst_r, c, r);
    imageStore(u_dst_g, c, g);
    imageStore(u_dst_b, c, b);
#if defined(MODE_ACCUMULATE)
    // Only Kaplanyan's intensity lookup reads the accumulated coefficients.
    imageStore(u_accum_r, c, imageLoad(u_accum_r, c) + r);
    imageStore(u_accum_g, c, imageLoad(u_accum_g, c) + g);
    imageStore(u_accum_b, c, imageLoad(u_accum_b, c) + b);
#endif
    // Flux that moved this step (|band-0| is the flux each cell now holds), for the adaptive stop.
    float moved_flux = abs(sh_flux(r)) + abs(sh_flux(g)) + abs(sh_flux(b));
    if (moved_flux > 0.0) atomicAdd(moved, int(round(moved_flux * u_flux_scale)));
}
