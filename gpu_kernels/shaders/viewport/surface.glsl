// SPDX-License-Identifier: GPL-3.0-or-later
// The viewport's surfaces, drawn with Blender's gpu module (ui/draw.py declares the inputs through
// gpu.types.GPUShaderCreateInfo, so this file holds only the stages' bodies): light looked up in the surface atlas
// (gpu_kernels/surface/), where the render's own passes computed Diffuse Direct and Diffuse Indirect per texel —
// uploaded already multiplied by the texel's base colour — times the view-dependent diffuse share of the
// material from the same table the G-buffer reads (common/principled.glsl: row 0 of each material, D(μ) at
// texel centres μ = k/(n−1)), plus emission: Cycles' Combined without the glossy part, from any camera, with no
// GI pass per view.
//
// The indirect light has an atlas of its own, coarser than the direct light's (it varies slowly): each vertex
// carries its place in both (tile / box, tile_i / box_i). `material`: rgb the diffuse share where it does not
// depend on the view (variant CONSTANT_SHARE), a the material's row in the part's table or polynomial texture.
//
// On a software GL (llvmpipe) every fragment instruction is paid ~500 000 times a redraw, so ui/draw.py compiles a
// variant per case instead of branching per pixel, and whatever is the same over a triangle, or affine over it,
// is worked out per vertex: which page of the atlas the camera sees, the tile's clamp bounds, the normal's sign,
// texel coordinates already divided by the atlas's size. The variants (ui/draw_parts.py picks them):
//   the share — CONSTANT_SHARE: where the material's does not depend on the view (Diffuse BSDF, Principled with
//     no specular layer), a vertex attribute, and the fragment skips the view vector; POLY_SHARE: where a
//     polynomial in μ fits it (common/principled.share_polynomial, within draw.POLY_TOLERANCE of the table), a few
//     multiply-adds per fragment instead of a filtered texture lookup, one channel of them where the three are
//     the same (GREY_SHARE); else the table (a coat's steep Fresnel, a smooth lobe);
//   FLAT_NORMAL: the triangle's three normals are the same, so the vertex hands it on flat, unit and turned to
//     the camera, and the fragment normalizes only the view vector;
//   DIRECT_LIGHT, INDIRECT_LIGHT: the light the display mode shows (both for Combined; emission with the direct).
//
// Push constants: u_view_projection; u_eye (xyz camera position, w 1 if orthographic); u_forward (xyz unit view
// axis, w depth pulled toward the camera, in clip w — the overlay draws over Blender's own copy of the same
// surfaces); u_pages (the direct and the indirect atlas's page heights in texels).

#if defined(VERTEX_SHADER)
void main() {
    vec3 to_eye = u_eye.w > 0.5 ? -u_forward.xyz : u_eye.xyz - pos;
    // Two-sided as in Cycles: seen from behind, the surface is lit by the atlas's back page. dot(geo, eye - p)
    // is the same at every point of the triangle's plane, so the provoking vertex decides for the triangle.
    bool back = dot(geo, to_eye) < 0.0;
    // Texel coordinates as texture() takes them, [0, 1] over the atlas: the division is affine, so done at the
    // corners it is done for every fragment.
    vec2 size = vec2(textureSize(u_direct, 0)), size_i = vec2(textureSize(u_indirect, 0));
    v_tile = tile / size;
    v_tile_i = tile_i / size_i;
    // Stay on this triangle's texel centres: the 2×2 footprint never reaches a neighbouring tile.
    v_clamp = vec4(box.xy + 0.5, box.xy + vec2(box.z) - 0.5) / size.xyxy;
    v_clamp_i = vec4(box_i.xy + 0.5, box_i.xy + vec2(box_i.z) - 0.5) / size_i.xyxy;
    vec2 page = back ? u_pages / vec2(size.y, size_i.y) : vec2(0.0);
    v_emission = emission;
#if defined(CONSTANT_SHARE)
    v_page = page;
    v_share = material.rgb;
#else
    v_page = vec4(page, back ? -1.0 : 1.0, material.a);
    // eye - p is affine in p, so interpolated it is the fragment's own view vector.
    v_view = to_eye;
#if defined(FLAT_NORMAL)
    v_normal = v_page.z * normalize(nrm);
#else
    v_normal = nrm;
#endif
#endif
#if defined(POLY_SHARE)
    // The material's share polynomial (common/principled.share_polynomial): row material.a of u_share_poly,
    // two texels per channel — fetched per vertex and handed on flat, so no fragment touches a texture for it.
    ivec2 row = ivec2(0, int(material.a + 0.5));
    v_r0 = texelFetch(u_share_poly, row, 0);
    v_r1 = texelFetch(u_share_poly, row + ivec2(1, 0), 0);
#if !defined(GREY_SHARE)
    v_g0 = texelFetch(u_share_poly, row + ivec2(2, 0), 0);
    v_g1 = texelFetch(u_share_poly, row + ivec2(3, 0), 0);
    v_b0 = texelFetch(u_share_poly, row + ivec2(4, 0), 0);
    v_b1 = texelFetch(u_share_poly, row + ivec2(5, 0), 0);
#endif
#endif
    gl_Position = u_view_projection * vec4(pos, 1.0);
    gl_Position.z -= u_forward.w * gl_Position.w;
}
#endif

#if defined(FRAGMENT_SHADER)
void main() {
#if defined(CONSTANT_SHARE)
    vec3 share = v_share;
#else
    // The material's diffuse share at μ = n·v (one inverse square root for both lengths, or for v alone where the
    // normal comes unit).
#if defined(FLAT_NORMAL)
    float mu = clamp(dot(v_normal, v_view) * inversesqrt(dot(v_view, v_view)), 0.0, 1.0);
#else
    float mu = clamp(v_page.z * dot(v_normal, v_view) * inversesqrt(dot(v_normal, v_normal) * dot(v_view, v_view)),
                     0.0, 1.0);
#endif
#if defined(POLY_SHARE)
    // Σ c_k t^k, t = 2μ − 1, k < 8: the powers in two vec4s, a channel's coefficients in two more.
    float t = 2.0 * mu - 1.0;
    vec4 low = vec4(1.0, t, t * t, t * t * t);
    vec4 high = low * (low.z * low.z);
#if defined(GREY_SHARE)
    vec3 share = vec3(dot(v_r0, low) + dot(v_r1, high));
#else
    vec3 share = vec3(dot(v_r0, low) + dot(v_r1, high), dot(v_g0, low) + dot(v_g1, high),
                      dot(v_b0, low) + dot(v_b1, high));
#endif
#else
    // Its table row is layer v_page.w of u_material_lut, a 1D array texture, so linear filtering blends two
    // texels, not four.
    float size = float(textureSize(u_material_lut, 0).x);
    vec3 share = texture(u_material_lut, vec2((mu * (size - 1.0) + 0.5) / size, v_page.w)).rgb;
#endif
#endif
    // The atlases are uploaded with linear filtering (draw.rgba_texture): a bilinear lookup is one fetch.
    vec3 light = vec3(0.0);
#if defined(DIRECT_LIGHT)
    light += texture(u_direct, clamp(v_tile, v_clamp.xy, v_clamp.zw) + vec2(0.0, v_page.x)).rgb;
#endif
#if defined(INDIRECT_LIGHT)
    light += texture(u_indirect, clamp(v_tile_i, v_clamp_i.xy, v_clamp_i.zw) + vec2(0.0, v_page.y)).rgb;
#endif
    out_color = vec4(share * light, 1.0);
#if defined(DIRECT_LIGHT)
    out_color.rgb += v_emission;
#endif
}
#endif
