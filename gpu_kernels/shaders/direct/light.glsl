// SPDX-License-Identifier: GPL-3.0-or-later
// Direct light per pixel from the G-buffer: sun, point, spot (Cycles' smoothstep cone), and polygon lights (area
// lights and emissive triangles), all shadowed through the shadow atlas. Outputs Cycles' Diffuse Direct pass
// (irradiance/π, polygons integrated exactly with Lambert's formula) and, where the surface has a glossy closure
// and u_glossy_enabled, its Glossy Direct pass: the GGX reflection of every light toward the camera (direct/ggx.glsl)
// with Cycles' energy scale 1/E(μ), Glossy Color divided out (docs/conventions.md).
#include "common/lights.glsl"
#include "common/light_eval.glsl"
#include "direct/eval.glsl"
#include "direct/ggx.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_diffuse_direct;
layout(rgba32f, binding = 1) uniform writeonly image2D u_glossy_direct;
uniform sampler2D u_position;      // xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform sampler2D u_geo_normal;    // xyz geometric normal (faces the viewer)
uniform sampler2D u_glossy;        // rgb Glossy Color, w roughness
uniform sampler2D u_specular;      // rgb base colour, w material index
uniform sampler2D u_material_lut;  // common/principled.py: material_lut
uniform bool u_glossy_enabled;     // a camera G-buffer (the surface atlas has no view direction)
uniform vec3 u_eye;
uniform vec3 u_forward;
uniform bool u_ortho;
uniform int u_light_count;
uniform ivec2 u_size;
// The pass runs once per group of lights (direct/lighting.py light_groups): these u_group_count lights.
uniform int u_group_count;
layout(std430, binding = 9) readonly buffer GroupLights { int group_lights[]; };
// The sky light's shares come from the sky_visibility pass (MODE_SKY, direct/sky.py) where u_sky_cached:
// they depend on the G-buffer and the sky's shadow maps only, so a world colour edit reads them back.
uniform bool u_sky_cached;
uniform sampler2D u_sky_shares;
#if defined(MODE_SKY)
layout(rgba32f, binding = 2) uniform writeonly image2D u_sky_out;     // shares (direct/sky.glsl sky_result)
// After an object's move (direct/sky.py): the shares of one update ago, kept outside u_moved_pixels where no test
// reads a texel the move redrew (direct/sky.glsl sky_reads_redrawn)
uniform bool u_sky_update;
uniform sampler2D u_sky_prior;
#endif
// After an object's move (direct/lighting.Relight) only the pixels it can change are lit again: those inside
// u_moved_pixels (x0, y0, x1, y1: where the moved triangles can cover the G-buffer) and those whose shadow tests can
// read a texel that the depth atlas redrew (changed_views: a view of one of this group's lights and its redrawn
// rectangle). The others write alpha 0 and keep their earlier value. A uniform, not a define: the pixels lit again
// run the very code a cold render does, so they come out the same to the bit.
uniform bool u_masked;
uniform ivec4 u_moved_pixels;
uniform int u_changed_count;
struct ChangedView {
    ivec4 index;   // x: the view, y: its light
    vec4 rect;     // the texels redrawn, in atlas texels: x0, y0, x1, y1
};
layout(std430, binding = 10) readonly buffer ChangedViews { ChangedView changed_views[]; };

// Whether a shadow test of light L at p reads a texel of `c`'s rectangle: q is p biased as the tests bias it (for
// v0, the view or its cube's first face, whose eye and texel size every face shares), projected into c's view,
// and the reads reach as far as the PCF radius or a polygon light's blocker search (polygon_visibility's patch of
// half-size h, at most MAX_SEARCH_SHARE of the map's side), plus a texel of bilinear footprint.
bool reads_changed(ChangedView c, GpuLight L, ShadowView v0, vec3 q, vec3 p) {
    ShadowView v = shadow_views[c.index.x];
    vec4 clip = v.view_projection * vec4(q, 1.0);
    if (clip.w <= 0.0) return false;   // behind the view's eye: no test reads it
    vec2 texel = (v.tile.xy + (clip.xy / clip.w * 0.5 + 0.5) * v.tile.zw) / u_atlas_texel;
    float reach = v.info.y;
    if (int(L.color_type.w) == LIGHT_POLYGON && L.polygon.z < 0.5) {
        vec4 e = v0.emitter;
        float h = 0.5 * sqrt(e.w * max(dot(e.xyz, normalize(p - v0.origin.xyz)), 0.0));
        reach = max(reach, min(4.0 * h / (length(q - v.origin.xyz) * v.info.x),
                               MAX_SEARCH_SHARE * v.tile.z / u_atlas_texel.x));
    }
    reach += 2.0;
    return all(greaterThan(texel, c.rect.xy - reach)) && all(lessThan(texel, c.rect.zw + reach));
}

// Whether no shadow test of this group at p reads a redrawn texel and p's G-buffer texel is not one the move can
// cover. A cube's tests read the one face its biased point falls in (cube_visibility), so q and that face are
// found once per cube (changed_views lists the views in order).
bool unchanged(ivec2 px, vec3 p, vec3 geo_n) {
    if (all(greaterThanEqual(px, u_moved_pixels.xy)) && all(lessThan(px, u_moved_pixels.zw))) return false;
    int first = -1, face = -1;
    vec3 q = p;
    for (int k = 0; k < u_changed_count; ++k) {
        ChangedView c = changed_views[k];
        GpuLight L = lights[c.index.y];
        int base = int(L.params.y);
        bool cube = int(L.params.w) == 6;
        int f = cube ? base + (c.index.x - base) / 6 * 6 : c.index.x;
        ShadowView v0 = shadow_views[f];
        if (f != first) {
            first = f;
            int type = int(L.color_type.w);
            vec3 to_light = v0.origin.w > 0.5 ? -L.direction.xyz
                          : normalize((type == LIGHT_SPOT ? L.position.xyz : v0.origin.xyz) - p);
            q = biased_point(v0, p, geo_n, to_light, MAX_SLOPE);
            face = cube ? f + cube_face(q - v0.origin.xyz) : f;
        }
        if (c.index.x == face && reads_changed(c, L, v0, q, p)) return false;
    }
    return true;
}

#include "direct/sky.glsl"

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    bool inside = all(lessThan(px, u_size));
    vec4 pos = inside ? texelFetch(u_position, px, 0) : vec4(0.0);
#if defined(MODE_SKY)
    bool moved = all(greaterThanEqual(px, u_moved_pixels.xy)) && all(lessThan(px, u_moved_pixels.zw));
    bool updated = u_sky_update && pos.w >= 0.5 && !moved;
#endif
    if (!inside) return;
    if (pos.w < 0.5) {
#if defined(MODE_SKY)
        imageStore(u_sky_out, px, vec4(0.0));
#else
        imageStore(u_diffuse_direct, px, vec4(0.0, 0.0, 0.0, 1.0));
        imageStore(u_glossy_direct, px, vec4(0.0, 0.0, 0.0, 1.0));
#endif
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    vec3 geo_n = normalize(texelFetch(u_geo_normal, px, 0).xyz);
#if !defined(MODE_SKY)
    if (u_masked && unchanged(px, pos.xyz, geo_n)) {
        imageStore(u_diffuse_direct, px, vec4(0.0));
        imageStore(u_glossy_direct, px, vec4(0.0));
        return;
    }
#endif
    vec4 glossy = u_glossy_enabled ? texelFetch(u_glossy, px, 0) : vec4(0.0);
    bool has_glossy = max(glossy.r, max(glossy.g, glossy.b)) > 0.0;
    vec4 spec = texelFetch(u_specular, px, 0);
    vec3 v = u_ortho ? -u_forward : normalize(u_eye - pos.xyz);
    GlossyLobe lobe = GlossyLobe(glossy.w * glossy.w, int(spec.w + 0.5), dot(n, v), spec.rgb);
    bool lobe_seen = has_glossy && lobe.mu > 0.0;
#if defined(MODE_SKY)
    vec3 sky = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i)
        if (int(lights[i].color_type.w) == LIGHT_SKY)
            sky = updated && !sky_reads_redrawn(lights[i], pos.xyz, geo_n)
                ? texelFetch(u_sky_prior, px, 0).xyz
                : sky_result(sky_sums(lights[i], pos.xyz, n, geo_n, lobe, v, lobe_seen), int(lights[i].params.z));
    imageStore(u_sky_out, px, vec4(sky, 0.0));
    return;
#endif
    vec3 irradiance = vec3(0.0), reflected = vec3(0.0), world = vec3(0.0);
    GlossyFresnel fresnel = glossy_fresnel_rows(u_material_lut, lobe.material, lobe.mu, lobe.base);
    for (int j = 0; j < u_group_count; ++j) {
        int i = group_lights[j];
        if (int(lights[i].color_type.w) == LIGHT_SKY) {
            // The world: irradiance π·L and, for any roughness, its reflection L (Glossy Color divided out; Cycles
            // counts the world a mirror shows as direct light too), each times its share of the sky that is seen.
            float unused;
            vec2 shares = u_sky_cached ? texelFetch(u_sky_shares, px, 0).xy
                                       : sky_shares(lights[i], pos.xyz, n, geo_n, lobe, v, lobe_seen, unused);
            irradiance += light_unshadowed(lights[i], pos.xyz, n) * shares.x;
            if (lobe_seen) world += lights[i].color_type.rgb * shares.y;
            continue;
        }
        vec3 e = light_unshadowed(lights[i], pos.xyz, n);
        vec3 g = has_glossy ? light_glossy(fresnel, lobe, lights[i], pos.xyz, n, v) : vec3(0.0);
        if (max(max(e.r, e.g), max(max(e.b, g.r), max(g.g, g.b))) <= 0.0) continue;
        float vis = light_visibility(lights[i], pos.xyz, n, geo_n);
        irradiance += e * vis;
        reflected += g * vis;
    }
    float e_mu = max(principled_ggx_albedo(u_material_lut, lobe.material, lobe.mu), 1e-4);
    vec3 glossy_direct = has_glossy ? reflected / (e_mu * max(glossy.rgb, vec3(1e-6))) + world : vec3(0.0);
    imageStore(u_diffuse_direct, px, vec4(irradiance / PI, 1.0));
    imageStore(u_glossy_direct, px, vec4(glossy_direct, 1.0));
}
