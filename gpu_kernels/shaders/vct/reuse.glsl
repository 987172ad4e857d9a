// SPDX-License-Identifier: GPL-3.0-or-later
// The last view's diffuse gathers reused after a camera move (reverse reprojection caching, Nehab et al. 2007,
// "Accelerating real-time shading with reverse reprojection caching"): bounced light does not depend on the camera,
// so a sample whose surface point the last view gathered at can take that gather's value. vct/reuse.py says when.
//
// One invocation per texel of the reduced-resolution trace (vct/trace.glsl: texel i gathers at G-buffer pixel
// i·s + s/2). Its point p is projected into the last view, and of the 3 × 3 last samples around it the one kept is
// the gather made (its origin: the point it was traced at, carried along when reused again)
//   - on p's surface: normals within u_normal_cos, each point within u_plane metres of the other's tangent plane;
//   - nearest to p as the new camera sees it, and no farther than u_reach texels (VctSettings.reuse_reach, ≤ 1:
//     the upsampling, vct/upsample.glsl, already blends samples a texel apart on one surface; the 3 × 3 searched
//     hold every last sample within a texel of p's projection). The distance is from the origin, never from the last
//     texel, so a value reused over many moves never drifts further.
// A texel no last sample passes for is marked (a = −1) and traced (vct/trace.glsl MODE_MARKED). Without a last
// view (MODE_SEED) every texel is marked and only the origins are written.
layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_position;      // this view's G-buffer: xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal (faces the viewer)
uniform ivec2 u_image_size;        // this view's traced size
uniform ivec2 u_full_size;         // this view's G-buffer size
uniform int u_scale;               // G-buffer pixels per traced texel (both views)
uniform mat4 u_view_projection;    // this view's world → clip
layout(rgba32f, binding = 0) uniform writeonly image2D u_indirect;  // rgb Diffuse Indirect, a AO (or −1: trace)
layout(rgba32f, binding = 1) uniform writeonly image2D u_origin;    // xyz where the value was traced, w hit flag
layout(rgba32f, binding = 2) uniform writeonly image2D u_origin_normal;
layout(std430, binding = 3) buffer Counter { uint marked; uint reused; };
layout(std430, binding = 5) writeonly buffer MarkedList { ivec2 marked_texels[]; };  // for vct/trace.glsl MODE_MARKED
#if !defined(MODE_SEED)
uniform sampler2D u_last;          // the last view's traced texture, its origins and their normals
uniform sampler2D u_last_origin;
uniform sampler2D u_last_normal;
uniform ivec2 u_last_size;         // its traced size and G-buffer size
uniform ivec2 u_last_full_size;
uniform mat4 u_last_view_projection;
uniform float u_reach;             // texels of this view
uniform float u_plane;             // metres
uniform float u_normal_cos;

// Where world point x falls on a G-buffer of `full` pixels (pixel units, pixel i's centre at i + 0.5), or a far-off
// point if x lies behind that camera.
vec2 pixel_of(mat4 view_projection, vec3 x, ivec2 full) {
    vec4 clip = view_projection * vec4(x, 1.0);
    if (clip.w <= 0.0) return vec2(-1e9);
    return (clip.xy / clip.w * 0.5 + 0.5) * vec2(full);
}

// The last texel whose gather p may take (see above), or (−1, −1). `src`: the G-buffer pixel p was read at (the
// texel's, clamped to the image), from whose centre the reach is measured.
ivec2 last_sample(ivec2 src, vec3 p, vec3 n) {
    vec2 last = (pixel_of(u_last_view_projection, p, u_last_full_size) - 0.5 - float(u_scale / 2)) / float(u_scale);
    ivec2 centre = ivec2(round(last));
    ivec2 best = ivec2(-1);
    float nearest = u_reach;
    for (int k = 0; k < 9; ++k) {
        ivec2 j = centre + ivec2(k % 3 - 1, k / 3 - 1);
        if (any(lessThan(j, ivec2(0))) || any(greaterThanEqual(j, u_last_size))) continue;
        vec4 o = texelFetch(u_last_origin, j, 0);
        if (o.w < 0.5) continue;
        vec3 on = texelFetch(u_last_normal, j, 0).xyz;
        if (dot(n, on) < u_normal_cos) continue;
        if (max(abs(dot(n, o.xyz - p)), abs(dot(on, p - o.xyz))) > u_plane) continue;
        float d = distance(pixel_of(u_view_projection, o.xyz, u_full_size), vec2(src) + 0.5) / float(u_scale);
        if (d <= nearest) {
            nearest = d;
            best = j;
        }
    }
    return best;
}
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
    ivec2 src = min(px * u_scale + u_scale / 2, u_full_size - 1);
    vec4 pos = texelFetch(u_position, src, 0);
    if (pos.w < 0.5) {  // background: nothing to trace (vct/trace.glsl writes 0 there)
        imageStore(u_indirect, px, vec4(0.0));
        imageStore(u_origin, px, vec4(0.0));
        imageStore(u_origin_normal, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, src, 0).xyz);
#if !defined(MODE_SEED)
    ivec2 j = last_sample(src, pos.xyz, n);
    if (j.x >= 0) {
        atomicAdd(reused, 1u);
        imageStore(u_indirect, px, texelFetch(u_last, j, 0));
        imageStore(u_origin, px, texelFetch(u_last_origin, j, 0));
        imageStore(u_origin_normal, px, texelFetch(u_last_normal, j, 0));
        return;
    }
#endif
    marked_texels[atomicAdd(marked, 1u)] = px;
    imageStore(u_indirect, px, vec4(0.0, 0.0, 0.0, -1.0));
    imageStore(u_origin, px, vec4(pos.xyz, 1.0));
    imageStore(u_origin_normal, px, vec4(n, 0.0));
}
