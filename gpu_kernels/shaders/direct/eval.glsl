// SPDX-License-Identifier: GPL-3.0-or-later
// Shadowed direct irradiance of one light at a point (sun, point, spot, polygon), shared by the Diffuse Direct
// pass (direct/light.glsl) and VCT radiance injection (vct/inject.glsl), so voxels are lit exactly like pixels.
// Needs the light/view/polygon buffers of common/lights.glsl and the shadow atlas declared here.
#pragma once
#include "common/lights.glsl"
#include "common/light_eval.glsl"


#define OFFSET_TEXELS 1.5  // normal offset of a shadow test, in shadow texels
// The slope-scaled part of a light's test's offset is capped at tan θ = MAX_SLOPE: more moved shadows' edges (up to
// 17 texels off the surface at 8: a sofa lit by the sun through the wall 2 cm beside a window's edge), less lets
// surfaces at grazing angles shadow themselves (a textured floor's speckles at 0).
#define MAX_SLOPE 1.0
uniform sampler2DShadow u_shadow_atlas;
uniform sampler2D u_shadow_depth;  // the same atlas's depths, read without comparison (gl/bind.RAW_DEPTH_UNIT)
uniform vec2 u_atlas_texel;        // 1 / atlas size
// Every u_sky_stride-th direction of the sky is read: 1 for pixels, common/lights.SKY_INJECTION_STRIDE for the
// voxels' injection.
uniform int u_sky_stride;

// Visibility of world point p from one shadow view with a normal-offset bias and percentage-closer filtering.
// The offset grows with the shadow texel's world footprint, which removes acne without a hand-tuned constant.
vec3 biased_point(ShadowView v, vec3 p, vec3 geo_n, vec3 to_light, float max_slope) {
    bool ortho = v.origin.w > 0.5;
    float dist = ortho ? 1.0 : length(p - v.origin.xyz);
    float texel_world = v.info.x * dist;
    float cos_l = clamp(dot(geo_n, to_light), 0.0, 1.0);
    float sin_l = sqrt(max(0.0, 1.0 - cos_l * cos_l));
    // 1.5 texels along the normal, more at grazing angles (slope-scaled), capped.
    return p + geo_n * texel_world * (OFFSET_TEXELS + 2.0 * min(sin_l / max(cos_l, 0.05), max_slope));
}

// Atlas uv and stored depth of world point x in view v (rasterised z for an orthographic view, radial distance /
// far for a perspective one); false where x lies behind the view's eye.
bool view_project(ShadowView v, vec3 x, out vec2 atlas_uv, out float depth) {
    vec4 clip = v.view_projection * vec4(x, 1.0);
    atlas_uv = vec2(0.0);
    depth = 0.0;
    if (clip.w <= 0.0) return false;
    vec3 ndc = clip.xyz / clip.w;
    atlas_uv = v.tile.xy + (ndc.xy * 0.5 + 0.5) * v.tile.zw;
    depth = v.origin.w > 0.5 ? ndc.z * 0.5 + 0.5 : length(x - v.origin.xyz) / v.info.z;
    return true;
}

// Whether atlas uv lies in view v's tile (outside it: nothing the map holds blocks the point).
bool in_tile(ShadowView v, vec2 atlas_uv) {
    return all(greaterThanEqual(atlas_uv, v.tile.xy)) && all(lessThanEqual(atlas_uv, v.tile.xy + v.tile.zw));
}

// Where the test of view `view_index` at p reads: the atlas uv of p biased (biased_point) and its depth as the
// shadow pass stored it; false where p lies behind the view's eye or outside its map (unshadowed).
bool view_uv_depth_biased(ShadowView v, vec3 p, vec3 geo_n, vec3 to_light, float max_slope, out vec2 atlas_uv,
                          out float depth) {
    return view_project(v, biased_point(v, p, geo_n, to_light, max_slope), atlas_uv, depth) && in_tile(v, atlas_uv);
}

// How the stored depth of the plane through q (normal geo_n) changes per atlas uv around q's own: a tap of a wide
// region beside q is compared with that plane there, not with q's depth, so the receiver does not shadow itself
// across the region (receiver plane depth bias: Isidoro 2006, "Shadow mapping: GPU-based tips and techniques").
// Zero where the plane holds the view's rays (it covers no texel).
vec2 receiver_slope(ShadowView v, vec3 q, vec3 geo_n, vec2 atlas_uv, float depth) {
    float size = v.info.x * (v.origin.w > 0.5 ? 1.0 : length(q - v.origin.xyz));   // a texel's world size at q
    vec3 t1 = normalize(cross(geo_n, abs(geo_n.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
    vec3 t2 = cross(geo_n, t1);
    vec2 uv1, uv2;
    float z1, z2;
    if (!view_project(v, q + size * t1, uv1, z1) || !view_project(v, q + size * t2, uv2, z2)) return vec2(0.0);
    mat2 m = mat2(uv1 - atlas_uv, uv2 - atlas_uv);
    if (abs(determinant(m)) < 1e-6 * dot(u_atlas_texel, u_atlas_texel)) return vec2(0.0);
    return inverse(transpose(m)) * vec2(z1 - depth, z2 - depth);
}

// With PCF radius 0 (the sky's maps) a test reads the four texels a gather at this point reads: a texel short of
// the tile's far edges, where a gather would read the next tile's first texels.
vec2 gather_point(ShadowView v, vec2 atlas_uv) {
    vec2 hi = v.tile.xy + v.tile.zw - 0.5 * u_atlas_texel;
    return clamp(atlas_uv, v.tile.xy + 0.5 * u_atlas_texel, hi - 0.5 * u_atlas_texel);
}

// How far in front of `depth` the nearest of the four texels around atlas_uv lies (≤ 0: none does): the stored
// depths compared as the atlas's "<=" comparison would.
float gather_gap(ShadowView v, vec2 atlas_uv, float depth) {
    vec4 z = textureGather(u_shadow_depth, gather_point(v, atlas_uv), 0);
    return depth - min(min(z.x, z.y), min(z.z, z.w));
}

// max_slope caps the slope-scaled part of the offset (MAX_SLOPE for a light's own maps; 0 for the sky's many directions: a
// grazing one pushed far off the surface would test a point beyond a thin wall, and acne in a few of them is
// averaged away).
// `gap`: with PCF radius 0, how far (in stored depth) the nearest of the four texels read lies in front of p (≤ 0:
// none does); 0 otherwise.
float view_test(int view_index, vec3 p, vec3 geo_n, vec3 to_light, float max_slope, out float gap) {
    gap = 0.0;
    ShadowView v = shadow_views[view_index];
    vec2 atlas_uv;
    float depth;
    if (!view_uv_depth_biased(v, p, geo_n, to_light, max_slope, atlas_uv, depth)) return 1.0;
    vec2 lo = v.tile.xy + 0.5 * u_atlas_texel;
    vec2 hi = v.tile.xy + v.tile.zw - 0.5 * u_atlas_texel;
    // PCF: a (2r+1)² grid of bilinear hardware comparisons.
    int r = int(v.info.y);
    // PCF radius 0 (the sky's maps): shadowed if any of the four texels around p is — a wall meeting the floor
    // at a grazing angle to the view changes depth by more than its distance to p across one texel, so the nearest
    // texel alone can read the wall as behind p and let the sky in at its foot (a wall seen edge-on covers no
    // texel at all: only the dilation keeps the sky out along a zero-thickness wall parallel to a direction). It
    // darkens each direction's visible region by a texel on every side: a few percent under a skylight.
    if (r == 0) {
        gap = gather_gap(v, atlas_uv, depth);
        return gap <= 0.0 ? 1.0 : 0.0;
    }
    float sum = 0.0;
    for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
            vec2 s = clamp(atlas_uv + vec2(i, j) * u_atlas_texel, lo, hi);
            sum += texture(u_shadow_atlas, vec3(s, depth));
        }
    return sum / float((2 * r + 1) * (2 * r + 1));
}

float view_visibility_biased(int view_index, vec3 p, vec3 geo_n, vec3 to_light, float max_slope) {
    float gap;
    return view_test(view_index, p, geo_n, to_light, max_slope, gap);
}

float view_visibility(int view_index, vec3 p, vec3 geo_n, vec3 to_light) {
    return view_visibility_biased(view_index, p, geo_n, to_light, MAX_SLOPE);
}

// The face is chosen for the biased point, the one the test projects: chosen for p, a point near a face's edge
// could be pushed out of that face's frustum (past its two-texel margin) and read as unshadowed — light came through
// closed walls where rays ran close to a cube seam (tests/stress/test_lights_camera.py). All six faces share the
// view's texel size, so the bias is the same whichever face is asked.
float cube_visibility(int first_view, vec3 p, vec3 geo_n) {
    vec3 origin = shadow_views[first_view].origin.xyz;
    vec3 to_light = normalize(origin - p);
    vec3 q = biased_point(shadow_views[first_view], p, geo_n, to_light, MAX_SLOPE);
    return view_visibility(first_view + cube_face(q - origin), p, geo_n, to_light);
}

#define PATCH_GATHERS 8            // at most, per axis: 2×2 texels each, over the region a blocker can shadow
#define MAX_SEARCH_SHARE 0.25      // that region's half-width cap, as a share of the map's side (64 of 256 texels)

// The share of [−h, h] that [c − w, c + w] covers, per axis.
vec2 patch_overlap(vec2 c, vec2 w, float h) {
    return max(min(vec2(h), c + w) - max(vec2(-h), c - w), vec2(0.0)) / (2.0 * h);
}

// Visibility from p of the patch of a polygon light that sample view `view_index` (a cube face at the sample point)
// stands for, half-size h (m) as p sees it, by backprojecting the shadow map's blockers onto the patch
// (Guennebaud et al. 2006, "Real-time soft shadow mapping by backprojection"). A texel at angle φ from p's
// direction (seen from the sample point) whose surface lies at distance z < d_r hides from p the patch's points at
// φ / (1/z − 1/d_r) from its centre — its own penumbra, so a blocker touching the receiver shadows sharply and one
// near the light softly, in the same pixel. The patch's covered share is summed over the texels around p's (their
// backprojections clamped to the patch; overlaps between blockers at different depths counted twice, then the
// sum clamped to 1). With the four sample points of a square light and a point's hard shadow each, a soft shadow
// was four hard ones, banded: the product shot's Diffuse Direct 3.4% off Cycles. A texel is a blocker only in front
// of the receiver's plane at that texel (Isidoro 2006, "Shadow mapping: GPU-based tips and techniques": receiver-
// plane depth bias), so the receiver does not shadow itself across the region. A patch too small for its penumbra to
// span two texels keeps the light's usual PCF.
float patch_visibility(int view_index, vec3 p, vec3 geo_n, vec3 to_light, float h) {
    ShadowView v = shadow_views[view_index];
    vec3 q = biased_point(v, p, geo_n, to_light, MAX_SLOPE);
    vec4 clip = v.view_projection * vec4(q, 1.0);
    if (clip.w <= 0.0) return 1.0;
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
    float d_r = length(q - v.origin.xyz);
    float tau = v.info.x;                      // a texel's angle (texel world size at unit distance)
    // Blockers at a fifth of the distance or farther: 1/z − 1/d_r ≤ 4/d_r.
    float search = min(4.0 * h / (d_r * tau), MAX_SEARCH_SHARE * v.tile.z / u_atlas_texel.x);
    if (search < 2.0) return view_visibility_biased(view_index, p, geo_n, to_light, MAX_SLOPE);
    vec3 c0;
    view_project(v, q, c0.xy, c0.z);
    vec2 grad = receiver_slope(v, q, geo_n, c0.xy, c0.z);   // the receiver plane's depth per atlas uv
    // Gathers read the 2 × 2 texels around their point: points within [lo, hi] keep them inside the tile.
    vec2 lo = v.tile.xy + 0.5 * u_atlas_texel;
    vec2 hi = v.tile.xy + v.tile.zw - 1.5 * u_atlas_texel;
    // The nearest blocker among 20 texels over that region sets how far the patch's shadow can reach: the
    // backprojection's region, over which its gathers are spread as densely as that allows.
    float nearest = 2.0;
    for (int k = 0; k < 5; ++k) {
        vec2 off = k < 4 ? (vec2(k & 1, k >> 1) * 2.0 - 1.0) * (0.5 * search) : vec2(0.0);
        vec2 centre = floor(clamp(c0.xy + off * u_atlas_texel, lo, hi) / u_atlas_texel - 0.5) + 1.0;
        vec4 z = textureGather(u_shadow_depth, centre * u_atlas_texel, 0);
        float ref = c0.z + dot(grad, (centre - c0.xy / u_atlas_texel) * u_atlas_texel);
        for (int i = 0; i < 4; ++i)
            if (z[i] < ref) nearest = min(nearest, z[i]);
    }
    if (nearest > 1.0) return view_visibility_biased(view_index, p, geo_n, to_light, MAX_SLOPE);
    float reach = h * (1.0 / max(nearest * v.info.z, 1e-6 * d_r) - 1.0 / d_r) / tau + 1.0;
    float region = clamp(reach, 2.0, search);
    // Gathers spaced `spacing` texels apart: each of their texels stands for the block of spacing/2 texels on its
    // side of the gather (at its centre: `corner` × spacing/2 from the gather's).
    int gathers = int(min(ceil(region), float(PATCH_GATHERS)));   // 2 texels apart where that covers the region
    float spacing = max(2.0, 2.0 * region / float(gathers));
    float half_block = 0.25 * spacing * tau;   // a block's half-width, as an angle
    vec2 texel_of_p = c0.xy / u_atlas_texel;   // p in atlas texels
    const vec2 corner[4] = vec2[4](vec2(-0.5, 0.5), vec2(0.5, 0.5), vec2(0.5, -0.5), vec2(-0.5, -0.5));  // gather order
    float covered = 0.0;
    for (int j = 0; j < gathers; ++j)
        for (int i = 0; i < gathers; ++i) {
            vec2 at = c0.xy + (vec2(i, j) - 0.5 * float(gathers - 1)) * spacing * u_atlas_texel;
            // snapped between four texel centres, so the gather's texels are known
            vec2 centre = floor(clamp(at, lo, hi) / u_atlas_texel - 0.5) + 1.0;
            vec4 z = textureGather(u_shadow_depth, centre * u_atlas_texel, 0);
            for (int k = 0; k < 4; ++k) {
                vec2 duv = (centre + corner[k] - texel_of_p) * u_atlas_texel;   // the texel read
                if (z[k] >= c0.z + dot(grad, duv)) continue;   // not in front of the receiver's plane
                float depth = z[k] * v.info.z;
                float k_inv = 1.0 / max(depth, 1e-6 * d_r) - 1.0 / d_r;
                if (k_inv <= 0.0) continue;
                vec2 at_block = centre + corner[k] * (0.5 * spacing) - texel_of_p;
                vec2 o = patch_overlap(at_block * tau / k_inv, vec2(half_block / k_inv), h);
                covered += o.x * o.y;
            }
        }
    return 1.0 - min(covered, 1.0);
}

// cube_visibility for a polygon light's sample point standing for a patch of half-size h (patch_visibility).
float cube_patch_visibility(int first_view, vec3 p, vec3 geo_n, float h) {
    vec3 origin = shadow_views[first_view].origin.xyz;
    vec3 to_light = normalize(origin - p);
    vec3 q = biased_point(shadow_views[first_view], p, geo_n, to_light, MAX_SLOPE);
    return patch_visibility(first_view + cube_face(q - origin), p, geo_n, to_light, h);
}

// Weighted visibility of a polygon light from its shadow sample points: each sample k stands for a share A_k of the
// light's area around it and emits along n_k (ShadowView.emitter), so it is weighted by its own unshadowed point
// contribution A_k · max(0, n_k·ω) · max(0, n·−ω) / d². A two-sided emitter has a sample on each side of its
// surface, each speaking only for receivers on its own side (but a closed one, which emits outwards only: its
// inner side has none, common/emitters.py).
float polygon_visibility(GpuLight L, vec3 p, vec3 n, vec3 geo_n) {
    int samples = int(L.params.z);
    if (samples == 0) return 1.0;
    int first = int(L.params.y);
    int per = int(L.params.w);
    // A one-sided polygon (an area light) is filtered per patch (cube_patch_visibility: the patch's half-size as p
    // sees it, its area A_k foreshortened). Emissive meshes keep hard shadows per sample: their samples sit a nudge
    // off a surface that curves around them (a lamp shade), whose own texels a backprojection reads as blockers.
    bool patches = L.polygon.z < 0.5;
    float wsum = 0.0, vsum = 0.0;
    for (int k = 0; k < samples; ++k) {
        int view0 = first + k * per;
        vec4 e = shadow_views[view0].emitter;
        vec3 d = p - shadow_views[view0].origin.xyz;
        float d2 = max(dot(d, d), 1e-8);
        vec3 w = d * inversesqrt(d2);
        float facing = max(dot(e.xyz, w), 0.0);
        float weight = e.w * facing * max(dot(n, -w), 0.0) / d2;
        if (weight <= 0.0) continue;
        wsum += weight;
        vsum += weight * (patches ? cube_patch_visibility(view0, p, geo_n, 0.5 * sqrt(e.w * facing))
                                  : cube_visibility(view0, p, geo_n));
    }
    // A receiver that no sample faces can still face some of a curved cluster's triangles at a grazing angle (a
    // wall beside a lamp shade whose cluster's samples lie on facets turned away): it is taken as shadowed. The
    // samples' maps see it only past their own facet, and lit unshadowed it was lit through a box closed around the
    // lamp (tests/gpu/test_emitters.py). More sample points make such receivers rarer (common/emitters.py).
    return wsum > 0.0 ? vsum / wsum : 0.0;
}

// Direction k of the sky light (ShadowView.emitter: d_k and its solid angle) as a surface of geometric normal
// geo_n sees it: false for directions below the surface (they see its back) and grazing ones (cos < SKY_MIN_COS: 1%
// of the irradiance), which would need an offset larger than a thin wall is thick; those take the others' mean (left
// out of both the weights and the visible sum).
#define SKY_MIN_COS 0.02
bool sky_direction(GpuLight L, int k, vec3 geo_n, out vec3 d) {
    d = shadow_views[int(L.params.y) + k].emitter.xyz;
    return dot(geo_n, d) >= SKY_MIN_COS;
}

// The angular radius of a sky direction's cell: a disc of the cell's solid angle 4π/K.
float sky_cell_radius(int samples) {
    return 2.0 / sqrt(float(samples));
}

// Metres per unit of an orthographic map's stored depth (its z is linear over its near–far span: 2 / |∇ ndc.z| of
// its view–projection).
float ortho_depth_scale(int view_index) {
    mat4 m = shadow_views[view_index].view_projection;
    return 2.0 / length(vec3(m[0][2], m[1][2], m[2][2]));
}

// How far (atlas texels) a sky cell's cone reads around its ray's texel in its map (direct/sky.glsl
// sky_cone_taps): the cell's radius at the farthest blocker the map can hold, its whole depth span.
float sky_reach(int view, int samples) {
    return tan(sky_cell_radius(samples)) * ortho_depth_scale(view) / shadow_views[view].info.x;
}

// Visibility of the sky light from its K directions d_k: the share of the cosine weight max(0, n·d_k) of the
// directions that reach the sky, one shadow test per direction (direct/light.glsl adds the glossy lobe's share to
// the same tests). A quadrature over the sphere of the visible share of the world; each direction's map holds the
// scene's own triangles, so thin and one-sided walls block exactly.
float sky_visibility(GpuLight L, vec3 p, vec3 n, vec3 geo_n) {
    int samples = int(L.params.z);
    if (samples == 0) return 1.0;
    float wsum = 0.0, vsum = 0.0;
    for (int k = 0; k < samples; k += max(u_sky_stride, 1)) {
        vec3 d;
        if (!sky_direction(L, k, geo_n, d)) continue;
        float w = max(dot(n, d), 0.0);
        if (w <= 1e-4) continue;
        wsum += w;
        vsum += w * view_visibility_biased(int(L.params.y) + k, p, geo_n, d, 0.0);
    }
    return wsum > 0.0 ? vsum / wsum : 0.0;
}

// A one-sided polygon light (an area light) shines along its `direction` only: p behind its plane gets nothing.
bool behind_polygon(GpuLight L, vec3 p) {
    return L.polygon.z < 0.5 && dot(p - L.position.xyz, L.direction.xyz) <= 0.0;
}

// Unshadowed direct irradiance of one light at p (normal n).
vec3 light_unshadowed(GpuLight L, vec3 p, vec3 n) {
    int type = int(L.color_type.w);
    vec3 color = L.color_type.rgb;
    if (type == LIGHT_SUN) return color * max(dot(n, -L.direction.xyz), 0.0);
    if (type == LIGHT_SKY) return color * PI;  // ∫ L·max(0, n·ω) dω over the sphere
    if (type == LIGHT_POINT || type == LIGHT_SPOT) {
        vec3 d = L.position.xyz - p;
        float d2 = max(dot(d, d), 1e-8);
        vec3 wi = d * inversesqrt(d2);
        float cosine = dot(n, wi);
        if (cosine <= 0.0) return vec3(0.0);
        float att = type == LIGHT_SPOT ? spot_attenuation(L, -wi) : 1.0;
        // position.w = r² for Cycles' soft-falloff disk (E = I·cosθ/(d²+r²)), 0 for a point or sphere light.
        return color * att * cosine / (d2 + L.position.w);
    }
    if (behind_polygon(L, p)) return vec3(0.0);
    return color * polygon_light_solid_angle(L, p, n);
}

// light_unshadowed for n (returned) and −n (`back`): both sides of a surface point, as VCT's injection lights them;
// an emissive mesh's triangles are evaluated once for the two.
vec3 light_unshadowed_sides(GpuLight L, vec3 p, vec3 n, out vec3 back) {
    if (int(L.color_type.w) == LIGHT_POLYGON) {
        back = vec3(0.0);
        if (behind_polygon(L, p)) return vec3(0.0);
        vec3 front = L.color_type.rgb * polygon_light_solid_angles(L, p, n, back);
        back *= L.color_type.rgb;
        return front;
    }
    back = light_unshadowed(L, p, -n);
    return light_unshadowed(L, p, n);
}

// The light's shadow-map visibility at p (1 for lights that cast no shadow).
float light_visibility(GpuLight L, vec3 p, vec3 n, vec3 geo_n) {
    if (L.params.z <= 0.0) return 1.0;
    int type = int(L.color_type.w);
    if (type == LIGHT_SUN) return view_visibility(int(L.params.y), p, geo_n, -L.direction.xyz);
    if (type == LIGHT_POINT) return cube_visibility(int(L.params.y), p, geo_n);
    if (type == LIGHT_SPOT) return view_visibility(int(L.params.y), p, geo_n, normalize(L.position.xyz - p));
    if (type == LIGHT_SKY) return sky_visibility(L, p, n, geo_n);
    return polygon_visibility(L, p, n, geo_n);
}

vec3 light_irradiance(GpuLight L, vec3 p, vec3 n, vec3 geo_n) {
    vec3 e = light_unshadowed(L, p, n);
    return max(e.r, max(e.g, e.b)) > 0.0 ? e * light_visibility(L, p, n, geo_n) : vec3(0.0);
}
