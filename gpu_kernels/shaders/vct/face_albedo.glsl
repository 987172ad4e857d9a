// SPDX-License-Identifier: GPL-3.0-or-later
// The voxel faces' albedo (vct/inject.face_albedo): per face g of voxel v, the mean albedo of the surface points
// whose side leaves the voxel through g, weighted as the injection weights their light (vct/inject_raster.glsl
// MODE_ALBEDO: the same points, the same w = A·|n_b|, covered sides left out), so that the face's radiance is
// albedo_g ⊙ E_g/π with E_g the injection's mean irradiance (vct/inject.glsl; vct/inject_sum.glsl multiplies).
// Kept apart from the light, a material's colour edit re-makes this and not the light, and apart from the voxel's
// mean albedo, a voxel holding a red wall and a white floor reflects red through its wall faces and white through
// its floor faces, and a rug over a floor the rug's colour only.
// A face with coverage (projected area on its axis) but no raster sample — a sliver thinner than the raster's
// pixels, which vct/inject.glsl lights at its centre — takes the mean of the same face of its 26 neighbours (the
// rest of its surface), else of its own voxel's other faces, else 0 (MODE_SLIVERS, over the list the resolve makes).
uniform ivec3 u_grid_size;
uniform sampler3D u_area;        // voxelize(): rgb projected areas (m²), a total area
uniform usampler3D u_acc;        // vct/inject_raster.glsl MODE_ALBEDO's sums (float bits), ACC_CHANNELS a face
layout(rgba16f, binding = 0) uniform writeonly image3D u_out[6];       // +x, −x, +y, −y, +z, −z
#include "vct/arrays.glsl"
VCT_STORE6(store_out, u_out)

float acc(ivec3 t) { return uintBitsToFloat(texelFetch(u_acc, t, 0).r); }

vec4 sums(int g, ivec3 v) {   // (Σ w·albedo, Σ w) of face g of voxel v
    ivec3 t = ivec3(ACC_CHANNELS * v.x, v.y, g * u_grid_size.z + v.z);
    return vec4(acc(t), acc(t + ivec3(1, 0, 0)), acc(t + ivec3(2, 0, 0)), acc(t + ivec3(3, 0, 0)));
}

vec4 neighbours(int g, ivec3 v) {
    vec4 sum = vec4(0.0);
    for (int k = 0; k < 27; ++k) {
        ivec3 u = v + ivec3(k % 3, (k / 3) % 3, k / 9) - 1;
        if (k != 13 && all(greaterThanEqual(u, ivec3(0))) && all(lessThan(u, u_grid_size))) sum += sums(g, u);
    }
    return sum;
}

#if defined(MODE_SLIVERS)
// The listed faces, one per invocation: the mean of the same face of the 26 neighbours, else of the voxel's other
// faces, else 0.
layout(local_size_x = 64) in;
layout(std430, binding = 5) readonly buffer Slivers { ivec4 slivers[]; };   // voxel, face g
uniform int u_first;   // this dispatch's first entry (at most 65535 groups a dispatch)
uniform int u_count;   // entries in the list

void main() {
    int i = u_first + int(gl_GlobalInvocationID.x);
    if (i >= u_count) return;
    ivec3 v = slivers[i].xyz;
    int g = slivers[i].w;
    vec4 s = neighbours(g, v);
    if (s.w <= 0.0)   // none around: the mean of the voxel's own other faces
        for (int f = 0; f < 6; ++f) s += sums(f, v);
    store_out(g, v, vec4(s.w > 0.0 ? s.rgb / s.w : vec3(0.0), 1.0));
}
#else
// Each covered face with samples gets their mean; a covered face without (a sliver) is listed for MODE_SLIVERS,
// whose neighbour search, run here, every lane of a SIMD group would have paid for its few slivers. Faces without
// coverage keep the zeros the images start with (gl/bind.texture3d): nothing reads them (vct/bounce.py gathers at
// covered faces, vct/inject_sum.glsl multiplies covered ones).
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
layout(std430, binding = 3) buffer Count { uint sliver_count; };   // gl/bind.dispatch_counted
layout(std430, binding = 5) writeonly buffer Slivers { ivec4 slivers[]; };
uniform uint u_capacity;   // entries the list holds: the count goes on past it (vct/inject.py makes it larger)

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 area = texelFetch(u_area, v, 0);
    if (area.a <= 0.0) return;
    for (int g = 0; g < 6; ++g) {
        if (!(area[g >> 1] > 0.0)) continue;
        vec4 s = sums(g, v);
        if (s.w > 0.0) {
            store_out(g, v, vec4(s.rgb / s.w, 1.0));
        } else {
            uint i = atomicAdd(sliver_count, 1u);
            if (i < u_capacity) slivers[i] = ivec4(v, g);
        }
    }
}
#endif
