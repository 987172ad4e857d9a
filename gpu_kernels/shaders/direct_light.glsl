// Direct diffuse light per pixel from the G-buffer: sun, point, spot (Cycles' smoothstep cone), and polygon lights
// (area lights and emissive triangles) integrated exactly with Lambert's polygon formula, all shadowed through the
// shadow atlas. Output is Cycles' Diffuse Direct pass: irradiance/π, albedo divided out (design.md §3).
#include "lights_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_diffuse_direct;
uniform sampler2D u_position;      // xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform sampler2D u_geo_normal;    // xyz geometric normal (faces the viewer)
uniform sampler2DShadow u_shadow_atlas;
uniform vec2 u_atlas_texel;        // 1 / atlas size
uniform int u_light_count;
uniform ivec2 u_size;

const float PI = 3.14159265358979;

// Visibility of world point p from one shadow view with a normal-offset bias and percentage-closer filtering.
// The offset grows with the shadow texel's world footprint, which removes acne without a hand-tuned constant.
float view_visibility(int view_index, vec3 p, vec3 geo_n, vec3 to_light) {
    ShadowView v = shadow_views[view_index];
    bool ortho = v.origin.w > 0.5;
    float dist = ortho ? 1.0 : length(p - v.origin.xyz);
    float texel_world = v.info.x * dist;
    float cos_l = clamp(dot(geo_n, to_light), 0.0, 1.0);
    float sin_l = sqrt(max(0.0, 1.0 - cos_l * cos_l));
    // 1.5 texels along the normal, more at grazing angles (slope-scaled), capped.
    vec3 q = p + geo_n * texel_world * (1.5 + 2.0 * min(sin_l / max(cos_l, 0.05), 8.0));
    vec4 clip = v.view_projection * vec4(q, 1.0);
    vec3 ndc = clip.xyz / clip.w;
    if (clip.w <= 0.0) return 1.0;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;  // outside: unshadowed
    // Same depth the shadow pass stored: rasterised z (ortho) or radial distance / far (perspective).
    float depth = ortho ? ndc.z * 0.5 + 0.5 : length(q - v.origin.xyz) / v.info.z;
    vec2 lo = v.tile.xy + 0.5 * u_atlas_texel;
    vec2 hi = v.tile.xy + v.tile.zw - 0.5 * u_atlas_texel;
    vec2 atlas_uv = v.tile.xy + uv * v.tile.zw;
    // PCF: a (2r+1)² grid of bilinear hardware comparisons.
    int r = int(v.info.y);
    float sum = 0.0;
    for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
            vec2 s = clamp(atlas_uv + vec2(i, j) * u_atlas_texel, lo, hi);
            sum += texture(u_shadow_atlas, vec3(s, depth));
        }
    return sum / float((2 * r + 1) * (2 * r + 1));
}

// Cube of six views around an origin (+X, -X, +Y, -Y, +Z, -Z): pick the face the direction falls in.
int cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x > 0.0 ? 0 : 1;
    if (a.y >= a.z) return d.y > 0.0 ? 2 : 3;
    return d.z > 0.0 ? 4 : 5;
}

float cube_visibility(int first_view, vec3 p, vec3 geo_n) {
    vec3 origin = shadow_views[first_view].origin.xyz;
    vec3 to_light = normalize(origin - p);
    return view_visibility(first_view + cube_face(p - origin), p, geo_n, to_light);
}

// ∫ over the polygon of cosθ dω (projected solid angle), polygon clipped to the upper hemisphere of n.
// Lambert's formula: Σ_edges angle(v_i, v_j) · n·normalize(v_i × v_j) / 2 (Arvo 1995, "Applications of irradiance
// tensors"), with atan2 for the edge angle so short edges stay accurate.
float polygon_projected_solid_angle(int first, int count, vec3 p, vec3 n) {
    vec3 clipped[MAX_POLYGON_VERTICES];
    int m = 0;
    // A receiver in the polygon's own plane (e.g. the emitter itself) sees it edge-on: zero projected solid angle.
    float max_height = 0.0, max_dist = 0.0;
    for (int i = 0; i < count; ++i) {
        vec3 a = polygon_vertices[first + i].xyz - p;
        max_height = max(max_height, dot(a, n));
        max_dist = max(max_dist, length(a));
    }
    if (max_height <= 1e-5 * max_dist) return 0.0;
    for (int i = 0; i < count; ++i) {
        vec3 a = polygon_vertices[first + i].xyz - p;
        vec3 b = polygon_vertices[first + (i + 1) % count].xyz - p;
        float ha = dot(a, n), hb = dot(b, n);
        if (ha >= 0.0 && m < MAX_POLYGON_VERTICES) clipped[m++] = a;
        if ((ha >= 0.0) != (hb >= 0.0) && m < MAX_POLYGON_VERTICES) clipped[m++] = a + (b - a) * (ha / (ha - hb));
    }
    if (m < 3) return 0.0;
    float sum = 0.0;
    for (int i = 0; i < m; ++i) {
        vec3 a = normalize(clipped[i]);
        vec3 b = normalize(clipped[(i + 1) % m]);
        vec3 c = cross(a, b);
        float s = length(c);
        if (s < 1e-12) continue;
        sum += atan(s, dot(a, b)) * dot(n, c) / s;
    }
    return abs(sum) * 0.5;
}

// Weighted visibility of a polygon light from its shadow sample points: each sample is weighted by its own
// unshadowed point contribution (cosθ_light · cosθ_receiver / d²), so samples that light p more count more.
float polygon_visibility(GpuLight L, vec3 p, vec3 n, vec3 geo_n) {
    int samples = int(L.params.z);
    if (samples == 0) return 1.0;
    int first = int(L.params.y);
    int per = int(L.params.w);
    vec3 ln = L.direction.xyz;
    bool two_sided = L.polygon.z > 0.5;
    float wsum = 0.0, vsum = 0.0;
    for (int k = 0; k < samples; ++k) {
        int view0 = first + k * per;
        vec3 o = shadow_views[view0].origin.xyz;
        vec3 d = p - o;
        float d2 = max(dot(d, d), 1e-8);
        vec3 w = d * inversesqrt(d2);
        // Two-sided emitters have one sample per side (even k: along the normal, odd k: against it); a sample
        // only speaks for receivers on its own side.
        vec3 side_n = (two_sided && (k % 2 == 1)) ? -ln : ln;
        float cl = max(dot(side_n, w), 0.0);
        float weight = cl * max(dot(n, -w), 0.0) / d2;
        if (weight <= 0.0) continue;
        wsum += weight;
        vsum += weight * cube_visibility(view0, p, geo_n);
    }
    return wsum > 0.0 ? vsum / wsum : 1.0;
}

vec3 light_irradiance(GpuLight L, vec3 p, vec3 n, vec3 geo_n) {
    int type = int(L.color_type.w);
    vec3 color = L.color_type.rgb;
    bool shadowed = L.params.z > 0.0;
    if (type == LIGHT_SUN) {
        vec3 wi = -L.direction.xyz;
        float cosine = dot(n, wi);
        if (cosine <= 0.0) return vec3(0.0);
        float vis = shadowed ? view_visibility(int(L.params.y), p, geo_n, wi) : 1.0;
        return color * cosine * vis;
    }
    if (type == LIGHT_POINT || type == LIGHT_SPOT) {
        vec3 d = L.position.xyz - p;
        float d2 = max(dot(d, d), 1e-8);
        vec3 wi = d * inversesqrt(d2);
        float cosine = dot(n, wi);
        if (cosine <= 0.0) return vec3(0.0);
        float att = 1.0;
        if (type == LIGHT_SPOT) {
            // Cycles (kernel/light/spot.h): smoothstep(0, 1, (cos α − cos(half size)) · smooth), smooth = 1/((1−cos half)·blend)
            float c = dot(-wi, L.direction.xyz);
            att = L.params.x > 0.0 ? smoothstep(0.0, 1.0, (c - L.direction.w) * L.params.x) : float(c > L.direction.w);
            if (att <= 0.0) return vec3(0.0);
        }
        float vis = 1.0;
        if (shadowed) {
            vis = type == LIGHT_POINT ? cube_visibility(int(L.params.y), p, geo_n)
                                      : view_visibility(int(L.params.y), p, geo_n, wi);
        }
        // position.w = r² for Cycles' soft-falloff disk (E = I·cosθ/(d²+r²)), 0 for a point or sphere light.
        return color * att * cosine / (d2 + L.position.w) * vis;
    }
    // Polygon light: one-sided lights shine along `direction` only.
    vec3 from_light = p - L.position.xyz;
    if (L.polygon.z < 0.5 && dot(from_light, L.direction.xyz) <= 0.0) return vec3(0.0);
    float psa = polygon_projected_solid_angle(int(L.polygon.x), int(L.polygon.y), p, n);
    if (psa <= 0.0) return vec3(0.0);
    float vis = shadowed ? polygon_visibility(L, p, n, geo_n) : 1.0;
    return color * psa * vis;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_size))) return;
    vec4 pos = texelFetch(u_position, px, 0);
    if (pos.w < 0.5) {
        imageStore(u_diffuse_direct, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    vec3 geo_n = normalize(texelFetch(u_geo_normal, px, 0).xyz);
    vec3 irradiance = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        irradiance += light_irradiance(lights[i], pos.xyz, n, geo_n);
    }
    imageStore(u_diffuse_direct, px, vec4(irradiance / PI, 1.0));
}
