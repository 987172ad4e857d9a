// SPDX-License-Identifier: GPL-3.0-or-later
// Unshadowed glossy reflection of one light toward the viewer: Cycles' GGX (α = roughness², the GGX distribution
// and Smith's height-correlated masking-shadowing, Walter et al. 2007; Heitz 2014) with each closure's Fresnel and
// weight (common/principled.glsl: glossy_fresnel_at), for Glossy Direct (direct/light.glsl). Polygon lights (area
// lights, emissive triangles) are integrated by quadrature over sub-triangles of their fan; the linearly transformed
// cosines of Heitz et al. 2016 would be exact for rough and smooth lobes alike, and are not done yet, so lobes much
// narrower than the polygon's sub-triangles alias.
#pragma once
#include "common/lights.glsl"
#include "common/light_eval.glsl"
#include "common/principled.glsl"

#define GLOSSY_POLYGON_SAMPLES 24  // quadrature points per polygon light (at least one per fan triangle)

// The surface's glossy lobe: roughness α, its material's rows in `lut`, μ = n·v, base colour.
struct GlossyLobe {
    float alpha;
    int material;
    float mu;
    vec3 base;
};

// The lobe's f(v, l)·cosθ_l: D·G2/(4 μ_v) times the closures' Fresnel-weighted albedo at h·v (`f`: the material's
// rows at the lobe's μ, glossy_fresnel_rows — read once per pixel, not once per light sample).
vec3 lobe_cos(GlossyFresnel f, GlossyLobe g, vec3 n, vec3 v, vec3 l) {
    float mu_l = dot(n, l);
    if (g.mu <= 0.0 || mu_l <= 0.0) return vec3(0.0);
    vec3 h = normalize(v + l);
    float a2 = g.alpha * g.alpha;
    float c2 = min(dot(n, h) * dot(n, h), 1.0);
    float t = 1.0 - c2 + a2 * c2;
    float d = a2 / (PI * t * t);
    float g2 = 1.0 / (1.0 + ggx_lambda(a2, g.mu) + ggx_lambda(a2, mu_l));
    return glossy_fresnel_at(f, dot(h, v)) * (d * g2 / (4.0 * g.mu));
}

// The weight of sky direction d in the glossy lobe's share of the sky (direct/light.glsl): the lobe's own
// f(v, d)·cosθ_d up to a constant, GGX D(h)/D(n) = (α²/t)² with Smith's G2 and the closures' Fresnel at h·v
// (`fresnel`: glossy_fresnel_rows at the lobe's μ). `a2`: α² widened to the directions' spacing by the caller.
float sky_lobe_weight(GlossyLobe g, GlossyFresnel fresnel, float a2, vec3 n, vec3 v, vec3 d) {
    float mu_l = dot(n, d);
    if (g.mu <= 0.0 || mu_l <= 0.0) return 0.0;
    vec3 h = normalize(v + d);
    float c2 = min(dot(n, h) * dot(n, h), 1.0);
    float t = 1.0 - c2 + a2 * c2;
    float g2 = 1.0 / (1.0 + ggx_lambda(a2, g.mu) + ggx_lambda(a2, mu_l));
    return (a2 / t) * (a2 / t) * g2 * dot(glossy_fresnel_at(fresnel, dot(h, v)), vec3(1.0 / 3.0));
}

// Σ over quadrature points of the polygon: radiance × f·cosθ_l × cosθ_emitter·dA / d². The polygon is read as
// triangles (common/light_eval.glsl: polygon_triangle), a fan or an emitter cluster's list, each triangle with its
// own radiance scale and, for two-sided emitters, its own normal.
vec3 polygon_glossy(GlossyFresnel f, GlossyLobe g, GpuLight L, vec3 p, vec3 n, vec3 v) {
    bool two_sided = L.polygon.z > 0.5;
    int count = polygon_triangle_count(L);
    int k = max(1, int(sqrt(float(GLOSSY_POLYGON_SAMPLES) / float(max(count, 1)))));
    float inv_k = 1.0 / float(k);
    vec3 sum = vec3(0.0);
    for (int t = 0; t < count; ++t) {
        vec3 a, b, c;
        vec4 scale;
        polygon_triangle(L, t, a, b, c, scale);
        bool both_faces = two_sided && scale.w < 0.5;   // a closed emitter's triangles emit outwards only
        vec3 tn = cross(b - a, c - a);
        float len = length(tn);
        if (!(len > 0.0)) continue;
        vec3 emit_n = two_sided ? tn / len : L.direction.xyz;
        float sub_area = 0.5 * len * inv_k * inv_k;
        vec3 tri = vec3(0.0);
        // Centroids of the k² sub-triangles: k(k+1)/2 pointing like the triangle, k(k−1)/2 flipped.
        for (int i = 0; i < k; ++i) {
            for (int j = 0; i + j < k; ++j) {
                for (int flip = 0; flip < 2; ++flip) {
                    if (flip == 1 && i + j >= k - 1) continue;
                    vec2 bc = (vec2(i, j) + (flip == 0 ? vec2(1.0 / 3.0) : vec2(2.0 / 3.0))) * inv_k;
                    vec3 q = a + (b - a) * bc.x + (c - a) * bc.y;
                    vec3 w = q - p;
                    float d2 = max(dot(w, w), 1e-10);
                    vec3 l = w * inversesqrt(d2);
                    float cos_e = -dot(emit_n, l);
                    cos_e = both_faces ? abs(cos_e) : max(cos_e, 0.0);
                    if (cos_e > 0.0) tri += lobe_cos(f, g, n, v, l) * (cos_e * sub_area / d2);
                }
            }
        }
        sum += scale.rgb * tri;
    }
    return L.color_type.rgb * sum;
}

// The light's glossy reflection toward v: Σ weight × darkening × F × f·cosθ (Glossy Color × Glossy Direct, before
// Cycles' 1/E energy scale, which direct/light.glsl applies); `f`: glossy_fresnel_rows of the lobe.
vec3 light_glossy(GlossyFresnel f, GlossyLobe g, GpuLight L, vec3 p, vec3 n, vec3 v) {
    if (g.alpha * g.alpha <= 5e-7) return vec3(0.0);  // Cycles evaluates no singular lobe against a light
    int type = int(L.color_type.w);
    if (type == LIGHT_SKY) return vec3(0.0);  // the world's reflection: direct/light.glsl, with its visibility
    vec3 color = L.color_type.rgb;
    if (type == LIGHT_SUN) return color * lobe_cos(f, g, n, v, -L.direction.xyz);
    if (type == LIGHT_POINT || type == LIGHT_SPOT) {
        vec3 d = L.position.xyz - p;
        float d2 = max(dot(d, d), 1e-8);
        vec3 wi = d * inversesqrt(d2);
        float att = type == LIGHT_SPOT ? spot_attenuation(L, -wi) : 1.0;
        return color * (att / (d2 + L.position.w)) * lobe_cos(f, g, n, v, wi);
    }
    if (!(L.polygon.z > 0.5) && dot(p - L.position.xyz, L.direction.xyz) <= 0.0) return vec3(0.0);
    return polygon_glossy(f, g, L, p, n, v);
}
