// SPDX-License-Identifier: GPL-3.0-or-later
// Principled BSDF's layering, read from the material table (common/principled.py: material_lut) with no other
// uniforms, so every pass that shades a surface (the camera's G-buffer, common/materials.glsl) colours it alike; the
// viewport's fragment shader (viewport/surface.glsl) reads row 0 of the same table through a 1D array texture of
// its own. Each material has five rows of texels over μ = n·v ∈ [0, 1]:
//   row 0: rgb D(μ), the share of the base colour in Cycles' Diffuse Color;  a: E(μ), the GGX lobe's albedo
//   row 1: rgb the coat's and the dielectric layer's Glossy Color;           a: s5(μ), the lobe-averaged Schlick weight
//   row 2: rgb the metallic closure's weight;                               a: E_avg
//   row 3: rgb F0 × tint of the dielectric layer;                           a: its s(μ) (F̄ = mix(F0, 1, s))
//   row 4: x the layer's η (1: none), y its real F0 (constant over μ)
#pragma once

vec4 principled_row(sampler2D lut, int row, float mu) {
    vec2 size = vec2(textureSize(lut, 0));
    float x = clamp(mu, 0.0, 1.0) * (size.x - 1.0) + 0.5;  // texel centres at μ = k/(n−1): linear filtering
    return texture(lut, vec2(x / size.x, (float(row) + 0.5) / size.y));
}

vec3 principled_diffuse(sampler2D lut, int material, float mu) {
    return principled_row(lut, 5 * material, mu).rgb;
}

// Glossy Color: the dielectric layers' albedo plus the metal's, F82-tint with F0 = the base colour (white tint):
// weight × (E + F_ms·(1 − E)) × mix(F0, 1, s5), F_ms from F_ss = mix(F0, 1, 1/21) (Kulla–Conty, as Cycles).
vec3 principled_glossy(sampler2D lut, int material, float mu, vec3 base) {
    vec4 a = principled_row(lut, 5 * material, mu);
    vec4 b = principled_row(lut, 5 * material + 1, mu);
    vec4 c = principled_row(lut, 5 * material + 2, mu);
    if (max(c.r, max(c.g, c.b)) <= 0.0) return b.rgb;
    vec3 f0 = clamp(base, 0.0, 1.0);
    vec3 fss = mix(f0, vec3(1.0), 1.0 / 21.0);
    vec3 fms = fss * c.a / (vec3(1.0) - fss * (1.0 - c.a));
    vec3 darkening = vec3(a.a) + fms * (1.0 - a.a);
    return b.rgb + c.rgb * darkening * mix(f0, vec3(1.0), b.a);
}

float fresnel_dielectric(float cos_i, float eta) {
    float c = abs(cos_i);
    float g2 = eta * eta - 1.0 + c * c;
    if (g2 <= 0.0) return 1.0;
    float g = sqrt(g2);
    float a = (g - c) / (g + c);
    float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

// A material's glossy closures at one μ (its rows of the table), for glossy_fresnel_at over many h·v.
struct GlossyFresnel {
    vec4 a, b, c, d, e;
    vec3 base;
};

GlossyFresnel glossy_fresnel_rows(sampler2D lut, int material, float mu, vec3 base) {
    return GlossyFresnel(principled_row(lut, 5 * material, mu), principled_row(lut, 5 * material + 1, mu),
                         principled_row(lut, 5 * material + 2, mu), principled_row(lut, 5 * material + 3, mu),
                         principled_row(lut, 5 * material + 4, mu), base);
}

// Σ over the glossy closures of weight × darkening × F(h·v), for Glossy Direct (direct/ggx.glsl): the metal's
// F82-tint (white tint: Schlick with F0 = the base colour) and the dielectric layer's F0 × tint blended to 1 by the
// real dielectric Fresnel, as Cycles' generalised Schlick does; each is its Glossy Color share times F(h·v)/F̄, so
// averaged over the lobe it gives back Glossy Color. (The coat's share is scaled like the layer's.)
vec3 glossy_fresnel_at(GlossyFresnel f, float hv) {
    vec3 k = vec3(0.0);
    if (f.e.x != 1.0) {
        float s = clamp((fresnel_dielectric(hv, f.e.x) - f.e.y) / (1.0 - f.e.y), 0.0, 1.0);
        k += f.b.rgb * mix(f.d.rgb, vec3(1.0), s) / max(mix(f.d.rgb, vec3(1.0), f.d.a), vec3(1e-6));
    } else {
        k += f.b.rgb;  // the coat alone
    }
    if (max(f.c.r, max(f.c.g, f.c.b)) > 0.0) {
        vec3 f0 = clamp(f.base, 0.0, 1.0);
        vec3 fss = mix(f0, vec3(1.0), 1.0 / 21.0);
        vec3 fms = fss * f.c.a / (vec3(1.0) - fss * (1.0 - f.c.a));
        k += f.c.rgb * (vec3(f.a.a) + fms * (1.0 - f.a.a)) * mix(f0, vec3(1.0), pow(1.0 - clamp(hv, 0.0, 1.0), 5.0));
    }
    return k;
}

// E(μ): the GGX lobe's albedo with Fresnel 1 at the material's roughness (Cycles' energy_scale is 1/E).
float principled_ggx_albedo(sampler2D lut, int material, float mu) {
    return principled_row(lut, 5 * material, mu).a;
}
