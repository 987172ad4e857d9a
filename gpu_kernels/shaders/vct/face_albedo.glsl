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
// rest of its surface), else of its own voxel's other faces, else 0.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
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

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 area = texelFetch(u_area, v, 0);
    if (area.a <= 0.0) return;   // the images start zeroed (gl/bind.texture3d)
    vec4 face[6], own = vec4(0.0);
    for (int g = 0; g < 6; ++g) {
        face[g] = sums(g, v);
        own += face[g];
    }
    for (int g = 0; g < 6; ++g) {
        vec4 s = face[g];
        if (s.w <= 0.0 && area[g >> 1] > 0.0) s = neighbours(g, v);
        if (s.w <= 0.0) s = own;
        store_out(g, v, vec4(s.w > 0.0 ? s.rgb / s.w : vec3(0.0), 1.0));
    }
}
