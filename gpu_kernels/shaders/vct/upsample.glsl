// SPDX-License-Identifier: GPL-3.0-or-later
// Discontinuity-aware upsampling of the reduced-resolution VCT gather (inferred lighting, Kircher and Lawrance 2009:
// light at a reduced resolution, with the bilinear filter biased by depth and a surface ID so light does not bleed
// across object edges). Here the low-resolution texels are the gathers at G-buffer pixels i·s + s/2 (vct/trace.glsl),
// so each one's exact position and normal are read back from the full-resolution G-buffer: a joint bilateral filter
// (Kopf et al. 2007) over the 2×2 texels around the pixel, weight = bilinear × plane × normal:
//   plane   exp(−(d/σ)²), d = the larger of the two point-to-tangent-plane distances, σ = u_sigma (metres, half a
//           voxel: surfaces closer than that share the voxels their cones start in, so their gathers barely differ;
//           two surfaces a voxel apart get e^(−4) and farther ones nothing);
//   normal  max(n·n_j, 0)^8 (a 30° crease keeps 0.32 of its weight, a right angle none; the cosine-weighted gather
//           itself turns with the normal).
// Where no texel lies on the pixel's surface (Σ weight < 1e-3: thin objects, silhouettes) the pixel is marked
// (a = −1) and vct/trace.glsl MODE_MARKED traces it at full resolution, so no pixel takes another surface's light.
layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_low;           // rgba: Diffuse Indirect, AO at ceil(W/s) × ceil(H/s)
uniform sampler2D u_position;      // full-resolution G-buffer: xyz world position, w hit flag
uniform sampler2D u_normal;        // xyz shading normal
uniform ivec2 u_image_size;        // full resolution
uniform ivec2 u_low_size;
uniform int u_scale;
uniform float u_sigma;             // plane-distance scale (m)
layout(rgba32f, binding = 0) uniform writeonly image2D u_out;
layout(std430, binding = 3) buffer Counter { uint marked; };
layout(std430, binding = 5) writeonly buffer MarkedList { ivec2 marked_texels[]; };  // for vct/trace.glsl MODE_MARKED

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_image_size))) return;
    vec4 pos = texelFetch(u_position, px, 0);
    if (pos.w < 0.5) {
        imageStore(u_out, px, vec4(0.0));
        return;
    }
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    // Texel i sits at pixel i·s + s/2, so pixel p lies at texel coordinate (p − s/2) / s.
    vec2 u = (vec2(px) - float(u_scale / 2)) / float(u_scale);
    ivec2 i0 = ivec2(floor(u));
    vec2 f = u - vec2(i0);
    vec4 sum = vec4(0.0);
    float wsum = 0.0;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 j = clamp(i0 + o, ivec2(0), u_low_size - 1);
        ivec2 q = min(j * u_scale + u_scale / 2, u_image_size - 1);
        vec4 qp = texelFetch(u_position, q, 0);
        if (qp.w < 0.5) continue;
        vec3 qn = normalize(texelFetch(u_normal, q, 0).xyz);
        vec2 b = mix(1.0 - f, f, vec2(o));
        float d = max(abs(dot(n, qp.xyz - pos.xyz)), abs(dot(qn, pos.xyz - qp.xyz))) / u_sigma;
        float c = max(dot(n, qn), 0.0);
        c *= c;
        c *= c;
        float w = b.x * b.y * exp(-d * d) * c * c;
        sum += w * texelFetch(u_low, j, 0);
        wsum += w;
    }
    if (wsum < 1e-3) {
        marked_texels[atomicAdd(marked, 1u)] = px;
        imageStore(u_out, px, vec4(0.0, 0.0, 0.0, -1.0));
        return;
    }
    imageStore(u_out, px, sum / wsum);
}
