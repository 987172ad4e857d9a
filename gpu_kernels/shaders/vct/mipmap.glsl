// SPDX-License-Identifier: GPL-3.0-or-later
// VCT radiance filtering (Freed 2018, §4.4: "a compute shader kernel is launched for each level ... averaging the
// surrounding 8 values"). Volumes store optical depth and τ-weighted radiance, rgb = τ·S, a = τ:
//   τ = optical depth of crossing one texel of that level (along the volume's axis when anisotropic),
//   S = the radiance it sends back toward the ray (W/(m²·sr)).
// Why τ and not the usual opacity α = 1 − e^−τ: trilinear filtering and the cone's discrete steps then integrate
// τ exactly — a hat-shaped τ profile sampled every half texel sums to the texel's τ for any phase — so a wall one
// voxel thick stops exactly as much of a cone as it should, wherever the samples fall. Filtering α instead smears
// an opaque wall into partially transparent samples whose product lets part of a cone through (measured, the
// anisotropic white furnace at 32³: 87.6% of the exact light with α stored, 92.4% with τ, all else equal; the
// isotropic one 39.5% with the α-averaged mips, 99.9% with the σ-average below). And τ·S interpolates to the
// τ-weighted mean radiance, the source function of the filtered medium. An opaque voxel gets
// τ_max = −ln(MIN_TRANSMITTANCE): it ends a cone, as an opaque voxel should (vct/common.glsl).
//
// MODE_BASE: level 0 from the six face radiances of vct_inject / vct_bounce (rgb = L_g, a = α_g, g = outward face
//   normal +x, −x, +y, −y, +z, −z), τ = −ln(1 − α) capped at τ_max.
//   isotropic: α = max_g α_g (= the voxelizer's opacity); S = the coverage-weighted mean over the three axes of the
//     brighter of the axis' two faces (per channel). One value must serve every direction. Taking the brighter side
//     keeps a wall lit on one side as bright as it is (the mean of both sides would halve it, since most walls are
//     dark on their back), at the price of the classic VCT leak: the back side glows too. Weighting the axes by
//     their projected areas keeps a voxel's few lit pixels of box top from lighting its whole side (taking the
//     brightest face overall made Cornell's Diffuse Indirect 2× too bright).
//   MODE_ANISO: volume f (direction of travel +x, −x, ...) holds the face a ray travelling that way sees, i.e. the
//     face whose normal points back at it: g = f ^ 1 (Crassin et al. 2011's directional voxels, down to level 0).
// MODE_DOWN: level l from level l − 1 (sizes are multiples of 2^max_level, so every parent has 8 children).
//   isotropic: the mean extinction coefficient σ = τ/V of the 8 children, so τ_parent = 2·mean τ (the parent is
//     twice as long), and likewise τ·S: Σ τ·S·V² (the filtered medium's emission) is conserved exactly, and a
//     wall that fills one layer of children keeps its optical depth (tests/gpu/test_vct.py).
//   MODE_ANISO: for direction f, the 4 columns of 2 children along f's axis are composited front to back in the
//     direction of travel, C = C_front + (1 − α_front)·C_back, α = α_front + (1 − α_front)·α_back (premultiplied
//     C = α·S), the columns averaged in (C, α) (see below why α and not τ), and stored back as τ = −ln(1 − α),
//     τ·S = τ·C/α. A wall one voxel thick stays opaque at every level for rays crossing it (Crassin et al. 2011).
// MODE_LAYERS (anisotropic only): where the surfaces of each texel lie along each axis, so that a cone can tell a
//   surface ahead of it from one behind it (vct/common.glsl, cone_step). rgb = τ_i·p_i for axis i: p_i the
//   τ-weighted mean coordinate (level-0 voxel units) of the texel's surfaces along i, τ_i its optical depth along
//   i (the same for both directions of travel: front-to-back compositing of α is symmetric). Stored multiplied by
//   τ_i so that trilinear filtering gives Σ w·τ·p, which divided by the filtered τ_i is the τ-weighted mean
//   position of the filtered texels. Level 0 from vct_inject's face centroids (the voxel centre for a face that
//   caught no raster sample), level l from the 8 children of level l − 1.
// MODE_READ: copy one level of u_src[0] into a buffer (tests and statistics; moderngl reads level 0 only).
// MODE_FLUX: per row (y, z) of the face textures, Σ_x Σ_g α_g·L_g (rgb), the occupied voxels and the faces that
//   caught no raster sample, for the statistics of vct.face_flux (no float atomics: rows summed here and on the CPU).
uniform ivec3 u_dst_size;   // size of the level written (or read)
uniform int u_level;

#if defined(MODE_FLUX)
layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler3D u_src[6];
uniform sampler3D u_centroid[6];
uniform bool u_has_centroids;
#include "vct/arrays.glsl"
VCT_FETCH6(src_face, u_src)
VCT_FETCH6(centroid_face, u_centroid)
layout(std430, binding = 0) writeonly buffer Out { vec4 rows[]; };   // 2 per row: (Σ α·L, occupied), (missed, 0…)
void main() {
    ivec2 yz = ivec2(gl_GlobalInvocationID.xy);
    if (yz.x >= u_dst_size.y || yz.y >= u_dst_size.z) return;
    vec4 sum = vec4(0.0);
    float missed = 0.0;
    for (int x = 0; x < u_dst_size.x; ++x) {
        float occupied = 0.0;
        for (int g = 0; g < 6; ++g) {
            vec4 f = src_face(g, ivec3(x, yz), 0);
            sum.rgb += f.a * f.rgb;
            occupied = max(occupied, float(f.a > 0.0));
            if (u_has_centroids && f.a > 0.0 && centroid_face(g, ivec3(x, yz), 0).w < 0.0) missed += 1.0;
        }
        sum.a += occupied;
    }
    int row = yz.y * u_dst_size.y + yz.x;
    rows[2 * row] = sum;
    rows[2 * row + 1] = vec4(missed, 0.0, 0.0, 0.0);
}
#elif defined(MODE_READ)
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_src[1];
layout(std430, binding = 0) writeonly buffer Out { vec4 texels[]; };
void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_dst_size))) return;
    texels[(v.z * u_dst_size.y + v.y) * u_dst_size.x + v.x] = texelFetch(u_src[0], v, u_level);
}
#elif defined(MODE_LAYERS)
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
uniform sampler3D u_src[6];       // the six direction volumes, every level built
uniform sampler3D u_centroid[6];  // level 0: vct_inject's centroids (xyz world, w = ±α_g, < 0 for a fallback face)
uniform sampler3D u_layers_src;   // this volume, read at level u_level − 1
uniform bool u_has_centroids;     // false: every voxel's surfaces are placed at its centre
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
layout(rgba32f, binding = 0) uniform writeonly image3D u_layers_dst;
#include "vct/arrays.glsl"
VCT_FETCH6(src_face, u_src)
VCT_FETCH6(centroid_face, u_centroid)
void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_dst_size))) return;
    vec3 out_ = vec3(0.0);
    for (int i = 0; i < 3; ++i) {
        float tau = src_face(2 * i, v, u_level).a;
        if (tau <= 0.0) continue;
        float p = float(v[i] << u_level) + 0.5 * float(1 << u_level);   // texel centre
        if (u_level == 0 && u_has_centroids) {
            vec4 cp = centroid_face(2 * i, v, 0), cm = centroid_face(2 * i + 1, v, 0);
            float sum = 0.0, n = 0.0;
            if (cp.w > 0.0) { sum += (cp[i] - u_grid_origin[i]) / u_grid_cell; n += 1.0; }
            if (cm.w > 0.0) { sum += (cm[i] - u_grid_origin[i]) / u_grid_cell; n += 1.0; }
            if (n > 0.0) p = sum / n;
        } else if (u_level > 0) {
            float weighted = 0.0, taus = 0.0;
            for (int k = 0; k < 8; ++k) {
                ivec3 c = 2 * v + ivec3(k & 1, (k >> 1) & 1, k >> 2);
                taus += src_face(2 * i, c, u_level - 1).a;
                weighted += texelFetch(u_layers_src, c, u_level - 1)[i];
            }
            if (taus > 0.0) p = weighted / taus;
        }
        out_[i] = tau * p;
    }
    imageStore(u_layers_dst, v, vec4(out_, 0.0));
}
#else
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
#define TAU_MAX 6.907755279   // −ln(1e-3) = −ln(MIN_TRANSMITTANCE) of vct/common.glsl

float depth_of(float alpha) { return min(-log(max(1.0 - alpha, 1e-30)), TAU_MAX); }

// Face (rgb = L, a = α) or composited (rgb = α·S, a = α) → stored (τ·S, τ).
vec4 stored(vec3 radiance, float alpha) {
    float tau = alpha > 0.0 ? depth_of(alpha) : 0.0;
    return vec4(tau * radiance, tau);
}

#if defined(MODE_ANISO)
#define VOLUMES 6
#else
#define VOLUMES 1
#endif
uniform sampler3D u_src[6];   // MODE_BASE: the six face textures; MODE_DOWN: the volumes at level u_level − 1
layout(rgba32f, binding = 0) uniform writeonly image3D u_dst[VOLUMES];
#include "vct/arrays.glsl"
VCT_FETCH6(src_face, u_src)
#if defined(MODE_ANISO)
VCT_STORE6(store_dst, u_dst)
#else
void store_dst(int i, ivec3 c, vec4 x) { imageStore(u_dst[0], c, x); }
#endif

#if defined(MODE_BASE)
void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_dst_size))) return;
    vec4 face[6];
    for (int g = 0; g < 6; ++g) face[g] = src_face(g, v, 0);
#if defined(MODE_ANISO)
    // A face without coverage would store zeros, which level 0 holds already: build_volumes zeroes it, and the
    // coverage is the geometry's, the same in every build into the same volumes (llvmpipe's image stores are slow,
    // and most voxels are empty).
    for (int f = 0; f < 6; ++f) {
        vec4 s = face[f ^ 1];
        if (s.a > 0.0) store_dst(f, v, stored(s.rgb, s.a));
    }
#else
    float alpha = 0.0, weight = 0.0;
    vec3 radiance = vec3(0.0);
    for (int axis = 0; axis < 3; ++axis) {
        vec4 plus = face[2 * axis], minus = face[2 * axis + 1];   // same coverage: one projected area per axis
        radiance += plus.a * max(plus.rgb, minus.rgb);
        weight += plus.a;
        alpha = max(alpha, plus.a);
    }
    if (alpha > 0.0) imageStore(u_dst[0], v, stored(weight > 0.0 ? radiance / weight : vec3(0.0), alpha));
#endif
}
#endif

#if defined(MODE_DOWN)
vec4 child(int f, ivec3 c) {
    return src_face(f, c, u_level - 1);
}

// Stored (τ·S, τ) → premultiplied (α·S, α).
vec4 premultiplied(vec4 t) {
    float alpha = 1.0 - exp(-t.a);
    return t.a > 0.0 ? vec4(alpha * t.rgb / t.a, alpha) : vec4(0.0);
}

#if defined(MODE_ANISO)
// One parent face f from its children. Called with f a constant for each face, not from a loop over f: llvmpipe
// runs every case of src_face's and store_dst's switches for an index it cannot fold (measured: the re-mips
// after each bounce took N times as long).
void down_face(int f, ivec3 v, ivec3 base) {
    int axis = f >> 1;
    ivec3 step = ivec3(0);
    step[axis] = 1;
    // Travelling +axis, the child with the lower coordinate is in front; travelling −axis, the higher one.
    bool forward = (f & 1) == 0;
    vec4 sum = vec4(0.0);   // premultiplied (α·S, α), composited per column
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            ivec3 c = base;
            int u = (axis + 1) % 3, w = (axis + 2) % 3;
            c[u] += i;
            c[w] += j;
            vec4 lo = premultiplied(child(f, c)), hi = premultiplied(child(f, c + step));
            vec4 front = forward ? lo : hi, back = forward ? hi : lo;
            sum += front + (1.0 - front.a) * back;
        }
    // The mean over the columns of α (the fraction of rays crossing the parent along f that are stopped), not
    // of τ: averaging τ enlarges a small bright object to the whole parent (Cornell's box tops, 6.5 W/(m²·sr),
    // took over their coarse texels: Cornell / courtyard Diffuse Indirect came out 15% / 8% brighter at 8
    // bounces, measured), at the price of some light through corners, where a coarse texel is half outside a
    // room (white furnace 5% low).
    sum *= 0.25;
    float tau = depth_of(sum.a);
    store_dst(f, v, sum.a > 0.0 ? vec4(tau * sum.rgb / sum.a, tau) : vec4(0.0));
}
#endif

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_dst_size))) return;
    ivec3 base = 2 * v;
#if defined(MODE_ANISO)
    down_face(0, v, base); down_face(1, v, base); down_face(2, v, base);
    down_face(3, v, base); down_face(4, v, base); down_face(5, v, base);
#else
    vec4 sum = vec4(0.0);
    for (int k = 0; k < 8; ++k) sum += child(0, base + ivec3(k & 1, (k >> 1) & 1, k >> 2));
    imageStore(u_dst[0], v, 0.25 * sum);   // 2 × the mean of 8
#endif
}
#endif
#endif
