// G-buffer from the scene camera: world position, shading normal, diffuse colour, emission, geometric normal.
// Sampled at pixel centres with no MSAA, like Cycles with a ~0.01 px pixel filter (design.md §3).
#if defined(VERTEX_SHADER)
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec3 in_geo_normal;
uniform mat4 u_view_projection;
out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
out vec3 v_geo_normal;
void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_uv = in_uv;
    v_geo_normal = in_geo_normal;
    gl_Position = u_view_projection * vec4(in_position, 1.0);
}
#endif

#if defined(FRAGMENT_SHADER)
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec3 v_geo_normal;
uniform vec3 u_camera_position;
uniform vec3 u_camera_forward;   // unit view axis, for planar depth (Cycles' Depth pass)
uniform bool u_camera_ortho;
uniform vec3 u_base_color;
uniform float u_metallic;
uniform float u_roughness;
uniform bool u_specular_layer;   // Principled BSDF: a dielectric GGX layer sits on the diffuse base
uniform vec3 u_emission;
uniform bool u_use_texture;
uniform sampler2D u_base_texture;
// Share of the base colour that Principled BSDF reflects diffusely, 1 − A_spec(roughness, μ = n·v), at IOR 1.5 and
// Specular IOR Level 0.5: Cycles scales the diffuse closure by (1 − albedo of the specular layer)
// (kernel/svm/closure.h, closure_layering_weight) and its Diffuse Color pass shows the scaled colour. Values are
// measured from Cycles 5.2.3's Diffuse Color pass (base 0.8); the μ = 0 row is the grazing limit (Fresnel → 1).
const float MU_ROWS[7] = float[](0.0, 0.087, 0.259, 0.5, 0.707, 0.866, 1.0);
const float ROUGH_COLS[6] = float[](0.0, 0.1, 0.25, 0.5, 0.75, 1.0);
const float DIFFUSE_SHARE[42] = float[](
    0.0,     0.0,     0.0,     0.0,     0.0,     0.0,
    0.37972, 0.40365, 0.59258, 0.81089, 0.90123, 0.93673,
    0.74670, 0.74811, 0.77558, 0.87651, 0.93345, 0.96122,
    0.91024, 0.91018, 0.91110, 0.93081, 0.95745, 0.97582,
    0.94950, 0.94944, 0.94898, 0.95284, 0.96740, 0.98179,
    0.95848, 0.95846, 0.95829, 0.96031, 0.97140, 0.98456,
    0.96000, 0.96000, 0.96011, 0.96262, 0.97320, 0.98621);

float principled_diffuse_share(float mu, float roughness) {
    mu = clamp(mu, 0.0, 1.0);
    roughness = clamp(roughness, 0.0, 1.0);
    int i = 0;
    while (i < 5 && mu > MU_ROWS[i + 1]) ++i;
    int j = 0;
    while (j < 4 && roughness > ROUGH_COLS[j + 1]) ++j;
    float ti = (mu - MU_ROWS[i]) / (MU_ROWS[i + 1] - MU_ROWS[i]);
    float tj = (roughness - ROUGH_COLS[j]) / (ROUGH_COLS[j + 1] - ROUGH_COLS[j]);
    float a = mix(DIFFUSE_SHARE[i * 6 + j], DIFFUSE_SHARE[i * 6 + j + 1], tj);
    float b = mix(DIFFUSE_SHARE[(i + 1) * 6 + j], DIFFUSE_SHARE[(i + 1) * 6 + j + 1], tj);
    return mix(a, b, ti);
}

layout(location = 0) out vec4 out_position;      // xyz world position, w = 1 where geometry was hit
layout(location = 1) out vec4 out_normal;        // xyz shading normal facing the viewer, w = planar depth
layout(location = 2) out vec4 out_albedo;        // rgb Diffuse Color, w = 1
layout(location = 3) out vec4 out_emission;      // rgb emitted radiance (emission colour × strength)
layout(location = 4) out vec4 out_geo_normal;    // xyz geometric normal facing the viewer

void main() {
    vec3 view_dir = u_camera_ortho ? -u_camera_forward : normalize(u_camera_position - v_position);
    vec3 geo_n = normalize(v_geo_normal);
    vec3 n = normalize(v_normal);
    // Surfaces are two-sided as in Cycles: seen from behind, both normals flip toward the viewer.
    if (dot(geo_n, view_dir) < 0.0) {
        geo_n = -geo_n;
        n = -n;
    }
    vec3 color = u_base_color;
    if (u_use_texture) {
        color = texture(u_base_texture, v_uv).rgb;
    }
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(n, dot(v_position - u_camera_position, u_camera_forward));
    float share = (1.0 - u_metallic) * (u_specular_layer ? principled_diffuse_share(dot(n, view_dir), u_roughness) : 1.0);
    out_albedo = vec4(color * share, 1.0);
    out_emission = vec4(u_emission, 1.0);
    out_geo_normal = vec4(geo_n, 0.0);
}
#endif
