// SPDX-License-Identifier: GPL-3.0-or-later
// VCT light injection, compute half (the surface points are rasterised by vct/inject_raster.glsl).
//
// Per direction, not per side of the voxel normal: the voxelizer's normal is a mean of sign-canonicalised normals,
// which says nothing about which side faces a room at an edge or corner voxel (floor + wall average to a diagonal
// pointing into neither). So each of the six faces of a voxel (outward normal ±x, ±y, ±z) gets its own light
// and coverage:
//   E_g/π = Σ w·E/π / Σ w over the surface points whose lit side points through face g (vct/inject_raster.glsl;
//         the face's radiance is albedo_g ⊙ E_g/π, its albedo made apart, vct/face_albedo.glsl),
//   α_g = min(1, projected area onto the face's plane / cell²) from the voxelizer (the opacity of crossing the voxel
//         along that axis; the same for both faces of an axis), a tilted plane's column summed (column_area),
//   c_g = Σ w·p / Σ w, where those surface points lie (the bounce pass gathers from there).
// A face that has coverage but caught no fragment (a sliver thinner than the raster's pixels) falls back to one
// evaluation at the face centre with the face normal: E(centre + n_g·cell/2, n_g)/π. The resolve lists
// those faces and MODE_FALLBACK lights them, one per invocation: lit in the resolve, every voxel of a SIMD group paid
// for the group's few fallback faces, up to six times over (measured, the Cornell box's 3244 of them: 190 ms of
// resolve, 35 without the lighting).
// Emission is not injected: emissive triangles are lights (common/lights.py), so E already carries their light,
// and adding it again would count it twice (Cycles' Diffuse Indirect never holds emission). A closed emitter emits
// outwards only (common/emitters.py): its inner light would leak out of the voxels.
// The accumulator starts zeroed (gl/bind.zero_texture). MODE_RESOLVE writes the faces: rgb = E_g/π, a = α_g, and
// centroids: xyz = c_g, w = α_g (or the face centre and w = −α_g for a fallback face; w = 0 where the voxel has no
// surface); MODE_FALLBACK lights the fallback faces the resolve listed.
#if !defined(MODE_FALLBACK)
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // gl/bind.VOLUME_GROUP
#endif
uniform ivec3 u_grid_size;

#if defined(MODE_RESOLVE) || defined(MODE_FALLBACK)
#include "common/lights.glsl"
#include "common/light_eval.glsl"
#include "direct/eval.glsl"
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform int u_light_count;
uniform sampler3D u_area;        // voxelize(): rgb projected areas (m²), a total area
uniform sampler3D u_normal;      // xyz area-weighted mean canonical normal (voxel/voxelize.py)
uniform usampler3D u_acc;        // vct/inject_raster.glsl's sums (float bits)
// Six images per dispatch, not twelve: NVIDIA drivers allow 8 image units per stage (GL_MAX_IMAGE_UNITS, the
// spec's minimum; Mesa allows 32), so vct.inject() runs this twice — faces, then centroids (WRITE_CENTROIDS).
layout(rgba32f, binding = 0) uniform writeonly image3D u_out[6];       // +x, −x, +y, −y, +z, −z
#include "vct/arrays.glsl"
VCT_STORE6(store_out, u_out)

// The fallback faces: (voxel packed 10 bits an axis, face g, α_g bits, 0).
layout(std430, binding = 5) buffer Fallback { uvec4 fallback[]; };

vec3 face_point(ivec3 v, vec3 n) {   // the centre of v's face with outward normal n
    vec3 centre = u_grid_origin + (vec3(v) + 0.5) * u_grid_cell;
    return centre + n * (0.5 * u_grid_cell);
}

vec3 face_normal(int g) {
    vec3 n = vec3(0.0);
    n[g >> 1] = (g & 1) == 0 ? 1.0 : -1.0;
    return n;
}

#if defined(MODE_FALLBACK)
layout(local_size_x = 64) in;
uniform uint u_first;   // this dispatch's first entry (at most 65535 groups a dispatch)
uniform uint u_count;   // entries in the list

void main() {
    uint i = u_first + gl_GlobalInvocationID.x;
    if (i >= u_count) return;
    uvec4 f = fallback[i];
    ivec3 v = ivec3(f.x & 1023u, (f.x >> 10) & 1023u, f.x >> 20);
    int g = int(f.y);
    vec3 n = face_normal(g);
    vec3 p = face_point(v, n);
    vec3 e = vec3(0.0);
    for (int k = 0; k < u_light_count; ++k) e += light_irradiance(lights[k], p, n, n);
    store_out(g, v, vec4(e / PI, uintBitsToFloat(f.z)));
}
#else
layout(std430, binding = 3) buffer Count { uint fallback_count; };   // gl/bind.dispatch_counted
uniform uint u_capacity;   // entries the list holds: the count goes on past it (vct/inject.py makes it larger)

float acc(int g, ivec3 v, int c) {
    return uintBitsToFloat(texelFetch(u_acc, ivec3(ACC_CHANNELS * v.x + c, v.y, g * u_grid_size.z + v.z), 0).r);
}

// The projected area along `axis` that voxel v's surface covers in its column: its own, plus its two neighbours'
// along the axis where they hold the same surface. A plane turned off the axes lies in a staircase of voxels, and
// neighbours along a column cover complementary parts of it (0.4 and 0.6 of the face): their coverages add
// (Carpenter 1984, "The A-buffer"), where the volumes' compositing would multiply their transmittances as if they
// were separate layers, and every cone crossing the wall let part of itself through (tests/gpu/test_vct_off_grid.py:
// a closed room turned 30° kept 0.62 of its light over 8 bounces, 0.72 with the sum). "The same surface": lit on a
// common side along the axis, and coplanar — mean normals within 8° (COPLANAR = cos 8°). Curved surfaces are left
// out: a sphere's neighbouring voxels differ by more, and summing them made the floor under metals' spheres brighter
// (their voxels' faces average lit and unlit parts), Diffuse Indirect 0.142 -> 0.207.
#define COPLANAR 0.99
bvec2 sides(ivec3 v, int axis) {
    return bvec2(acc(2 * axis, v, 3) > 0.0, acc(2 * axis + 1, v, 3) > 0.0);
}

float column_area(ivec3 v, int axis, float own) {
    float sum = own;
    bvec2 mine = sides(v, axis);
    vec3 nv = texelFetch(u_normal, v, 0).xyz;
    for (int k = -1; k <= 1; k += 2) {
        ivec3 u = v;
        u[axis] += k;
        if (u[axis] < 0 || u[axis] >= u_grid_size[axis]) continue;
        bvec2 theirs = sides(u, axis);
        vec3 nu = texelFetch(u_normal, u, 0).xyz;
        bool coplanar = dot(nu, nv) > COPLANAR * length(nu) * length(nv);
        if (coplanar && ((mine.x && theirs.x) || (mine.y && theirs.y))) sum += texelFetch(u_area, u, 0)[axis];
    }
    return own > 0.0 ? sum : 0.0;
}

void main() {
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, u_grid_size))) return;
    vec4 area = texelFetch(u_area, v, 0);
    if (area.a <= 0.0) return;   // most voxels are empty, and the images start zeroed (vct._texture3d)
    float cell2 = u_grid_cell * u_grid_cell;
    for (int g = 0; g < 6; ++g) {
        int axis = g >> 1;
        vec3 n = face_normal(g);
        float alpha = min(1.0, column_area(v, axis, area[axis]) / cell2);
        vec3 radiance = vec3(0.0);   // E_g/π
        vec4 surface = vec4(face_point(v, n), 0.0);
        float w = acc(g, v, 3);
        if (alpha > 0.0 && w > 0.0) {
            radiance = vec3(acc(g, v, 0), acc(g, v, 1), acc(g, v, 2)) / w;
            surface = vec4(vec3(acc(g, v, 4), acc(g, v, 5), acc(g, v, 6)) / w, alpha);
        } else if (alpha > 0.0) {
            // Lit by MODE_FALLBACK; the centroid dispatch needs only where the face is.
#if !defined(WRITE_CENTROIDS)
            uint i = atomicAdd(fallback_count, 1u);
            if (i < u_capacity) fallback[i] = uvec4(uint(v.x) | (uint(v.y) << 10) | (uint(v.z) << 20), uint(g),
                                                    floatBitsToUint(alpha), 0u);
#endif
            surface.w = -alpha;
        }
#if defined(WRITE_CENTROIDS)
        store_out(g, v, surface);
#else
        store_out(g, v, vec4(radiance, alpha));
#endif
    }
}
#endif
#endif
