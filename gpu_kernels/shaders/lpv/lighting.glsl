// SPDX-License-Identifier: GPL-3.0-or-later
// Diffuse Indirect from the LPV. Three estimators of irradiance E at a surface point with normal n:
//
// MODE_RECEIVER_VOLUMES / MODE_RECEIVERS (the cached transport, lpv/transfer.py): the irradiance of the receivers
// near the point, one per voxel and dominant axis of its surfaces (lpv/receivers.py; see receiver_irradiance), from
// six dense volumes or a sparse index.
//
// MODE_FLUX (the gathered and propagated transports): the irradiance of the surface voxels near the point, from the
// flux fuzzy occlusion stopped there (lpv/absorb.glsl) or the gather: energy-exact, since irradiance × area summed
// over all surfaces is the absorbed flux. The eight geometry-volume cells around the point are blended trilinearly,
// skipping empty ones, taking each voxel's side that faces the same way as the point's normal.
//
// Otherwise, Kaplanyan's intensity lookup (as Elvek 2012, §3.3.1, describes it): irradiance at a G-buffer point is the
// accumulated intensity distribution convolved with the clamped cosine about −n (light arriving at the surface travels
// along −n), E = c · lobe(−n) / cell², where intensity / cell² is the radiance of a cell of cross-section cell² (the
// LPV stores radiant intensity per cell). Volumes are sampled trilinearly half a cell in front of the surface, matching
// the half-cell injection offset. Cascades: the finest cascade containing the point wins, blended into the next one
// over its outer cells so the border does not show. Output is Cycles' Diffuse Indirect pass: E/π.
#include "lpv/common.glsl"

#define MAX_CASCADES 4
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_diffuse_indirect;
uniform sampler2D u_position;
uniform sampler2D u_normal;
uniform sampler3D u_accum_r[MAX_CASCADES];
uniform sampler3D u_accum_g[MAX_CASCADES];
uniform sampler3D u_accum_b[MAX_CASCADES];
uniform vec3 u_grid_origin[MAX_CASCADES];
uniform float u_grid_cell[MAX_CASCADES];
uniform ivec3 u_grid_size[MAX_CASCADES];
uniform int u_cascades;
uniform float u_blend_cells;     // width of the blend band at a cascade's border, in its cells
uniform bool u_damping;          // Elvek 2012's directional-derivative damping against leaks
uniform ivec2 u_image_size;
#if defined(MODE_FLUX)
uniform sampler3D u_front[MAX_CASCADES];   // per fine voxel: rgb irradiance of its surfaces' front side, a = 1 if any
uniform sampler3D u_back[MAX_CASCADES];
uniform sampler3D u_voxel_normal[MAX_CASCADES];
uniform vec3 u_fine_origin[MAX_CASCADES];
uniform ivec3 u_fine_size[MAX_CASCADES];

// The irradiance of voxels within two fine cells of `centre` whose surfaces face along n (within 18°) and lie in
// this surface's plane (within 0.6 of a fine cell), weighted by distance; −1 if there is none.
vec3 same_surface_irradiance(int cascade, vec3 p, vec3 n, ivec3 centre) {
    float h = 0.5 * u_grid_cell[cascade];
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int dz = -2; dz <= 2; ++dz)
        for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) {
                ivec3 G = centre + ivec3(dx, dy, dz);
                if (any(lessThan(G, ivec3(0))) || any(greaterThanEqual(G, u_fine_size[cascade]))) continue;
                vec4 front = texelFetch(u_front[cascade], G, 0);
                if (front.a <= 0.0) continue;
                vec3 nv = texelFetch(u_voxel_normal[cascade], G, 0).xyz;
                if (abs(dot(n, nv)) * inversesqrt(max(dot(nv, nv), 1e-20)) < 0.95) continue;
                vec3 d = u_fine_origin[cascade] + (vec3(G) + 0.5) * h - p;
                if (abs(dot(d, n)) > 0.6 * h) continue;
                float w = exp(-dot(d, d) / (h * h));
                sum += w * (dot(n, nv) >= 0.0 ? front.rgb : texelFetch(u_back[cascade], G, 0).rgb);
                wsum += w;
            }
    return wsum > 0.0 ? sum / wsum : vec3(-1.0);
}

vec3 flux_irradiance(int cascade, vec3 p, vec3 n) {
    vec3 t = (p - u_fine_origin[cascade]) / (0.5 * u_grid_cell[cascade]) - 0.5;
    ivec3 base = ivec3(floor(t));
    vec3 f = t - vec3(base);
    vec3 sum = vec3(0.0), agreed = vec3(0.0);
    float wsum = 0.0, agreed_w = 0.0, best = 0.0;
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        ivec3 G = base + o;
        if (any(lessThan(G, ivec3(0))) || any(greaterThanEqual(G, u_fine_size[cascade]))) continue;
        vec4 front = texelFetch(u_front[cascade], G, 0);
        if (front.a <= 0.0) continue;
        // Conservative voxelisation marks a surface lying near a voxel boundary in the voxels on both sides; the
        // one behind it (centre more than half a voxel behind the point) holds this surface's back (a roof's
        // sunlit top under its ceiling): skip it.
        vec3 centre = u_fine_origin[cascade] + (vec3(G) + 0.5) * (0.5 * u_grid_cell[cascade]);
        if (dot(centre - p, n) < -0.3 * u_grid_cell[cascade]) continue;
        vec3 nv = texelFetch(u_voxel_normal[cascade], G, 0).xyz;
        float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y) * (o.z == 1 ? f.z : 1.0 - f.z);
        vec3 e = dot(n, nv) >= 0.0 ? front.rgb : texelFetch(u_back[cascade], G, 0).rgb;
        // A voxel whose surfaces face another way (a corner voxel holding a wall and the ceiling has a diagonal
        // mean normal, and the irradiance of that diagonal, which sees less of the room) says little about this
        // surface: its weight falls as cos¹⁶ of the angle between the normals — 0.72 at 11°, 0.16 at 27° (a
        // corner of two walls of unequal share), 0.004 at 45° — so a voxel of this surface alone wins wherever
        // there is one; only where none is close do the others speak. (A linear ramp that counted voxels within
        // 35° fully left a dark line along every junction: the corner voxel's irradiance averaged in.)
        float agree = abs(dot(n, nv)) * inversesqrt(max(dot(nv, nv), 1e-20));
        float a2 = agree * agree, a4 = a2 * a2, a8 = a4 * a4;
        float aw = w * a8 * a8;
        best = max(best, agree);
        sum += w * e;
        wsum += w;
        agreed += aw * e;
        agreed_w += aw;
    }
    // At a junction the eight may hold only corner voxels (both surfaces, a diagonal normal and its lower
    // irradiance): look a little further along this surface for voxels of it alone.
    if (best < 0.95) {
        vec3 near = same_surface_irradiance(cascade, p, n, ivec3(floor(t + 0.5)));
        if (near.r >= 0.0) return near;
    }
    if (agreed_w > 1e-3) return agreed / agreed_w;
    return wsum > 0.0 ? sum / wsum : vec3(0.0);
}
#elif defined(MODE_RECEIVERS) || defined(MODE_RECEIVER_VOLUMES)
// The cached transport's receivers (lpv/receivers.py): a voxel's surfaces split by the dominant axis of their
// normals, each with its front (+axis) and back irradiance. One cascade: the cached transport has no others.
//
// The eight fine voxels around p are blended trilinearly over those with a receiver (Σ w·E / Σ w); of the axes n
// leans along, weighted n_a² — the weights of an ambient cube (McTaggart 2004, Valve's Source engine): they sum to
// one, pick the floor's receiver for a floor however near a wall, and blend a curved surface's across axes — on the
// side n faces. Where no receiver of n's axes is near (a sliver), any of them. Voxels outside the fine grid count as
// empty.
uniform vec3 u_fine_origin[MAX_CASCADES];
uniform ivec3 u_fine_size[MAX_CASCADES];
#if defined(MODE_RECEIVER_VOLUMES)
// Six volumes of the fine grid, axis a's side s at 2a + s (receivers.LightVolumes): rgb the irradiance where a
// receiver is, a = 1 there, 0 elsewhere. Filtered linearly, their rgb and a are the sums above, so three fetches
// give the blend; clamped at the edge, a voxel beyond it repeats the edge one, which the normalisation cancels
// (as if it were empty). Premultiplied this way, texture filtering does the work on any GPU.
uniform sampler3D u_receiver_light[6];

vec3 receiver_irradiance(int cascade, vec3 p, vec3 n) {
    vec3 uvw = (p - u_fine_origin[cascade]) / (0.5 * u_grid_cell[cascade] * vec3(u_fine_size[cascade]));
    vec3 n2 = n * n;
    vec3 sum = vec3(0.0), any_sum = vec3(0.0);
    float wsum = 0.0, any_w = 0.0;
    for (int a = 0; a < 3; ++a) {
        vec4 e = texture(u_receiver_light[2 * a + (n[a] >= 0.0 ? 0 : 1)], uvw);
        sum += n2[a] * e.rgb;
        wsum += n2[a] * e.a;
        any_sum += e.rgb;
        any_w += e.a;
    }
    if (wsum > 1e-6) return sum / wsum;
    return any_w > 0.0 ? any_sum / any_w : vec3(0.0);
}
#else
// The same blend from a sparse index per fine voxel (grids whose six volumes would not fit
// receivers.LIGHT_VOLUME_BYTES): which axes it has receivers for (bits 0–2) and where its first is (the rest, × 8)
// in the light records, two vec4 per receiver (front, back; a = 1 where it receives).
uniform isampler3D u_index[MAX_CASCADES];
layout(std430, binding = 6) readonly buffer ReceiverRecords { vec4 records[]; };

vec3 receiver_irradiance(int cascade, vec3 p, vec3 n) {
    vec3 t = (p - u_fine_origin[cascade]) / (0.5 * u_grid_cell[cascade]) - 0.5;
    ivec3 base = ivec3(floor(t));
    vec3 f = t - vec3(base);
    vec3 n2 = n * n;
    vec3 sum = vec3(0.0), any_sum = vec3(0.0);
    float wsum = 0.0, any_w = 0.0;
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        ivec3 G = base + o;
        if (any(lessThan(G, ivec3(0))) || any(greaterThanEqual(G, u_fine_size[cascade]))) continue;
        int entry = texelFetch(u_index[cascade], G, 0).r;
        if ((entry & 7) == 0) continue;
        float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y) * (o.z == 1 ? f.z : 1.0 - f.z);
        int r = entry >> 3;
        for (int a = 0; a < 3; ++a) {
            if ((entry & (1 << a)) == 0) continue;
            vec4 e = records[2 * r + (n[a] >= 0.0 ? 0 : 1)];
            ++r;
            if (e.a <= 0.0) continue;
            sum += w * n2[a] * e.rgb;
            wsum += w * n2[a];
            any_sum += w * e.rgb;
            any_w += w;
        }
    }
    if (wsum > 1e-6) return sum / wsum;
    return any_w > 0.0 ? any_sum / any_w : vec3(0.0);
}
#endif
#endif

const float PI = 3.14159265358979;

vec3 sample_cascade(int i, vec3 p, vec3 n) {
    vec3 uvw = (p - u_grid_origin[i]) / (u_grid_cell[i] * vec3(u_grid_size[i]));
    vec4 r = texture(u_accum_r[i], uvw), g = texture(u_accum_g[i], uvw), b = texture(u_accum_b[i], uvw);
    if (u_damping) {
        // Elvek 2012, §3.3.1: where the SH coefficients grow against the normal (∇_n c · c < 0), the light comes
        // from behind the surface (a leak): damp it by how strongly the derivative disagrees.
        vec3 step = n * 0.5 / vec3(u_grid_size[i]);
        vec4 dc = texture(u_accum_r[i], uvw + step) - texture(u_accum_r[i], uvw - step)
                + texture(u_accum_g[i], uvw + step) - texture(u_accum_g[i], uvw - step)
                + texture(u_accum_b[i], uvw + step) - texture(u_accum_b[i], uvw - step);
        vec4 c = r + g + b;
        float agree = dot(c, dc);
        if (agree < 0.0) {
            float k = clamp(-agree / max(dot(c, c), 1e-20), 0.0, 1.0);
            r *= 1.0 - k; g *= 1.0 - k; b *= 1.0 - k;
        }
    }
    vec4 lobe = sh_clamped_cosine(-n);
    return max(vec3(dot(r, lobe), dot(g, lobe), dot(b, lobe)), vec3(0.0)) / (u_grid_cell[i] * u_grid_cell[i]);
}

// 1 well inside cascade i, falling to 0 over the last u_blend_cells cells before its border.
float cascade_weight(int i, vec3 p) {
    vec3 g = (p - u_grid_origin[i]) / u_grid_cell[i];
    vec3 edge = min(g, vec3(u_grid_size[i]) - g);
    float inner = min(edge.x, min(edge.y, edge.z)) - 0.5;
    return i == u_cascades - 1 ? float(inner >= -0.5) : clamp(inner / u_blend_cells, 0.0, 1.0);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
    vec4 pos = texelFetch(u_position, px, 0);
    if (pos.w < 0.5) {
        imageStore(u_diffuse_indirect, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    vec3 irradiance = vec3(0.0);
    float remaining = 1.0;
    for (int i = 0; i < u_cascades && remaining > 0.0; ++i) {
        vec3 p = pos.xyz + n * 0.5 * u_grid_cell[i];
        float w = cascade_weight(i, p) * remaining;
        if (w <= 0.0) continue;
#if defined(MODE_FLUX)
        irradiance += w * flux_irradiance(i, pos.xyz, n);
#elif defined(MODE_RECEIVERS) || defined(MODE_RECEIVER_VOLUMES)
        irradiance += w * receiver_irradiance(i, pos.xyz, n);
#else
        irradiance += w * sample_cascade(i, p, n);
#endif
        remaining -= w;
    }
    // Irradiance is never negative. The propagating transport's SH lobes are (clamp_negative off), so a face can
    // absorb negative flux where light has not yet arrived from the side it lobes towards: one propagation step
    // gave Combined −0.025 (tests/stress). The intensity lookup clamps the same way (sample_cascade).
    imageStore(u_diffuse_indirect, px, vec4(max(irradiance, vec3(0.0)) / PI, 1.0));
}
