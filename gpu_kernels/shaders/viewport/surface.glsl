// SPDX-License-Identifier: GPL-3.0-or-later
// The viewport's surfaces, drawn with Blender's gpu module (ui/draw.py declares the inputs through
// gpu.types.GPUShaderCreateInfo, so this file holds only the stages' bodies): light looked up in the surface atlas
// (gpu_kernels/surface/), where the render's own passes computed Diffuse Direct and Diffuse Indirect per texel —
// uploaded already multiplied by the texel's base colour — times the view-dependent diffuse share of the
// material as the G-buffer computes it (common/principled.glsl), plus emission: Cycles' Combined without the
// glossy part, from any camera, with no GI pass per view.
//
// The indirect light has an atlas of its own, coarser than the direct light's (it varies slowly): each vertex
// carries its place in both (tile / box, tile_i / box_i).
//
// Push constants: u_view_projection; u_eye (xyz camera position, w 1 if orthographic); u_forward (xyz unit view
// axis, w the direct atlas's page height in texels); u_params (x: 0 Combined, 1 indirect only, 2 direct only; y:
// depth pulled toward the camera, in clip w — the overlay draws over Blender's own copy of the same surfaces;
// z: the indirect atlas's page height).

#if defined(VERTEX_SHADER)
void main() {
    v_position = pos;
    v_normal = nrm;
    v_geo_normal = geo;
    v_tile = tile;
    v_box = box;
    v_tile_i = tile_i;
    v_box_i = box_i;
    v_mat = mat;
    v_emission = emission;
    gl_Position = u_view_projection * vec4(pos, 1.0);
    gl_Position.z -= u_params.y * gl_Position.w;
}
#endif

#if defined(FRAGMENT_SHADER)
#include "common/principled.glsl"

// Bilinear lookup at texel coordinate c (texel centres at +0.5): the textures are uploaded with linear filtering
// (draw.rgba_texture), so one fetch.
vec3 atlas_lookup(sampler2D atlas, vec2 c) {
    return texture(atlas, c / vec2(textureSize(atlas, 0))).rgb;
}

void main() {
    vec3 to_eye = u_eye.w > 0.5 ? -u_forward.xyz : u_eye.xyz - v_position;
    // Two-sided as in Cycles: seen from behind, the surface is lit by the atlas's back page.
    bool back = dot(v_geo_normal, to_eye) < 0.0;
    // Stay on this triangle's texel centres: the 2×2 footprint never reaches a neighbouring tile.
    vec2 c = clamp(v_tile, v_box.xy + 0.5, v_box.xy + vec2(v_box.z) - 0.5);
    vec2 c_i = clamp(v_tile_i, v_box_i.xy + 0.5, v_box_i.xy + vec2(v_box_i.z) - 0.5);
    // The material's diffuse share at μ = n·v (its rows in u_material_lut, index v_mat.x).
    vec3 n = normalize(v_normal) * (back ? -1.0 : 1.0);
    vec3 share = principled_diffuse(u_material_lut, int(v_mat.x + 0.5), dot(n, normalize(to_eye)));
    vec3 direct = share * atlas_lookup(u_direct, c + vec2(0.0, back ? u_forward.w : 0.0));
    vec3 indirect = share * atlas_lookup(u_indirect, c_i + vec2(0.0, back ? u_params.z : 0.0));
    int mode = int(u_params.x + 0.5);
    vec3 color = mode == 1 ? indirect : mode == 2 ? direct + v_emission : direct + indirect + v_emission;
    out_color = vec4(color, 1.0);
}
#endif
