// SPDX-License-Identifier: GPL-3.0-or-later
// Gathered transport (LpvSettings.transport = "gather"): the irradiance every surface voxel receives straight from a
// list of VPLs — the RSM's for the first bounce, the surface voxels' own clusters for each further one
// (lpv/cluster.glsl) — instead of through the propagation.
//
// Why: the face scheme (lpv/propagate.glsl) re-emits, at every cell, the flux each face received as a clamped
// cosine lobe toward that face. A lobe pointing up sends only 0.096 of its flux through the far face of the cell
// above and 0.376 through the side faces, so light leaving a lit floor turns sideways and back down within a few
// cells — in the Cornell box the ceiling got 0.14× and the floor 1.68× of Cycles' indirect light. Here light goes
// straight from each VPL to each voxel:
//
//   E = Φ · max(0, n_vpl·ω) · |n_voxel·ω| / (π·d² + A) · T
//
// — the irradiance of a Lambertian emitter of flux Φ at distance d (ω: unit vector VPL → voxel). A is the source's
// area, the disc limit: a Lambertian disc of area A gives Φ/(π·d² + A) on its axis, finite at d = 0. A cluster of
// voxels carries its area; an RSM VPL (k×k texels, a patch about a voxel wide) counts as a disc of radius h, the
// fine voxel size. T is the fuzzy visibility from the same surface voxels the geometry volume blocks with: the
// covered fractions of the surface planes the ray crosses, summed, T = max(0, 1 − their sum) (a face half
// covered lets half through, as in propagation; see transmittance).
//
// MODE_TRANSFER writes the kernel per receiver and source instead (lpv/transfer.py: the cached transport).
//
// The result is added, per side, to what lpv/absorb.glsl found (zeros: world light is the sky light's VPLs), so the flux
// lookup (lpv/lighting.glsl, MODE_FLUX) reads it unchanged; the next bounce's VPLs come from it (lpv/cluster.glsl).
#include "lpv/common.glsl"
#include "common/polygon.glsl"  // clip_quad, quad_projected_solid_angle

layout(local_size_x = 64) in;
#include "common/structs.glsl"
layout(std430, binding = 6) readonly buffer VplList { Vpl vpls[]; };
layout(std430, binding = 7) readonly buffer SurfaceVoxels { ivec4 surfaces[]; };  // fine voxels with surfaces
uniform int u_surface_count;
uniform int u_vpl_first;           // this dispatch's VPLs: [first, first + count) (see lpv/gather.gather)
uniform int u_vpl_count;
uniform sampler3D u_voxel_normal;   // fine voxels: mean sign-canonical normal
uniform sampler3D u_voxel_area;     // fine voxels: rgb projected areas, a = surface area (m²)
uniform sampler3D u_coverage;       // LPV cells: covered fraction of the x/y/z cross-sections (lpv/occlusion.py)
uniform sampler3D u_layers;         // LPV cells: where those surfaces lie along x/y/z, in cells
uniform bool u_occlusion;
uniform vec3 u_fine_origin;
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform ivec3 u_grid_size;
#if defined(MODE_TRANSFER)
layout(std430, binding = 8) writeonly buffer Transfer { vec2 transfer[]; };  // lpv/transfer.py
// An update after an edit (lpv/transfer.update_transfer): only pairs whose receiver or source is new (w / flux.w
// set) or whose ray passes through the changed box are evaluated; the others are marked NaN and keep their value.
uniform bool u_update;
uniform vec3 u_box_lo;
uniform vec3 u_box_hi;
// Per source: the min / max corner of its voxels' centres (lpv/clusters.Clusters.box), w unused.
layout(std430, binding = 9) readonly buffer SourceBoxes { vec4 source_boxes[]; };

bool crosses_box(vec3 a, vec3 b) {  // the segment a → b meets the box (slab test)
    vec3 d = b - a;
    vec3 inv = vec3(d.x != 0.0 ? 1.0 / d.x : 1e30, d.y != 0.0 ? 1.0 / d.y : 1e30, d.z != 0.0 ? 1.0 / d.z : 1e30);
    vec3 t0 = (u_box_lo - a) * inv, t1 = (u_box_hi - a) * inv;
    float enter = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z));
    float leave = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z));
    return enter <= leave && leave >= 0.0 && enter <= 1.0;
}
#else
layout(rgba32f, binding = 0) uniform image3D u_front;  // this bounce: rgb irradiance (W/m²), a = 1 if surface
layout(rgba32f, binding = 1) uniform image3D u_back;
layout(rgba32f, binding = 2) uniform image3D u_front_total;
layout(rgba32f, binding = 3) uniform image3D u_back_total;
#endif

const float PI = 3.14159265358979;
const float END_CELLS = 0.5;

vec3 step01(vec3 d) {
    return vec3(greaterThan(d, vec3(0.0)));
}
const float NEAR_FIELD = 9.0;  // (distance / disc radius)² below which a VPL is split in four
const float AXIS_PLANE = 0.985;  // a source whose normal is within 10° of an axis lies in that axis' plane

// Visibility between a VPL at `from` and a receiver `dist` away along unit `dir`: the ray walks the LPV cells it passes
// (the traversal of Amanatides and Woo 1987) and, in each, meets the cell's surfaces only if it crosses the plane where
// they lie inside the cell — one oblique plane, or one per axis where a floor meets a wall (u_coverage, u_layers:
// lpv/occlusion.crossing_layers) — then their covered fraction of the light is stopped, as the geometry volume stops it
// at a face in propagation. A ray passing a wall without crossing it is not dimmed (a trilinear density would, within a
// cell of every wall and corner). Crossings within END_CELLS along an axis of either end (along the plane's normal)
// belong to the VPL's or the receiver's own surface (the planes are the voxels' centres, off the surface by up to a
// quarter cell) and are not counted.
float transmittance(vec3 from, vec3 dir, float dist) {
    if (!u_occlusion) return 1.0;
    vec3 o = (from - u_grid_origin) / u_grid_cell;  // in cells
    float len = dist / u_grid_cell;
    ivec3 c = ivec3(floor(o));
    ivec3 step = ivec3(sign(dir));
    vec3 inv = vec3(dir.x != 0.0 ? 1.0 / dir.x : 1e30, dir.y != 0.0 ? 1.0 / dir.y : 1e30,
                    dir.z != 0.0 ? 1.0 / dir.z : 1e30);
    vec3 t_max = (vec3(c) + step01(dir) - o) * inv;
    vec3 t_delta = abs(inv);
    float t = 0.0, crossings = 0.0;
    int cells = u_grid_size.x + u_grid_size.y + u_grid_size.z + 3;  // a straight line visits no more
    for (int k = 0; k < cells && t < len; ++k) {
        float t_exit = min(t_max.x, min(t_max.y, t_max.z));
        if (all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, u_grid_size))) {
            vec4 coverage = texelFetch(u_coverage, c, 0);
            if (coverage.w < 0.0) {  // one plane: normal coverage.xyz, offset layers.w, covering −coverage.w
                float facing = dot(coverage.xyz, dir);
                float tc = (texelFetch(u_layers, c, 0).w - dot(coverage.xyz, o)) / (facing != 0.0 ? facing : 1e-30);
                if (tc >= t && tc < t_exit && abs(tc * facing) > END_CELLS && abs((len - tc) * facing) > END_CELLS)
                    crossings -= coverage.w;
            } else if (any(greaterThan(coverage.xyz, vec3(0.0)))) {  // axis planes
                vec3 tc = (texelFetch(u_layers, c, 0).xyz - o) * inv;  // where the ray meets each plane
                vec3 hit = vec3(greaterThanEqual(tc, vec3(t))) * vec3(lessThan(tc, vec3(t_exit)))
                         * vec3(greaterThan(abs(tc * dir), vec3(END_CELLS)))
                         * vec3(greaterThan(abs((len - tc) * dir), vec3(END_CELLS)));  // no loop: see vpls_per_dispatch
                crossings += dot(coverage.xyz, hit);
            }
            if (crossings >= 1.0) return 0.0;
        }
        int axis = t_max.x <= t_max.y ? (t_max.x <= t_max.z ? 0 : 2) : (t_max.y <= t_max.z ? 1 : 2);
        c[axis] += step[axis];
        t_max[axis] += t_delta[axis];
        t = t_exit;
    }
    return 1.0 - crossings;
}

#if defined(MODE_TRANSFER)
// Near a cluster that lies in an axis plane (a wall's, a floor's): the exact irradiance per watt of a Lambertian
// rectangle of uniform radiance Φ/(π·A) spanning its voxels in that plane — Lambert's formula over its edges
// (common/polygon.glsl clip_quad, quad_projected_solid_angle), each side of the receiver seeing the part above its
// plane. A receiver beside a wall's edge gets half its irradiance from the floor right next to it; the quarter
// discs below, 1–2 cells out, gave edges 0.7–0.9 of it in a closed box. False where a side sees a triangle or a
// pentagon of it (the quarter discs then): clipping those needs arrays, which llvmpipe keeps in memory for the
// whole shader (2.5× slower).
bool rectangle_kernel(int j, Vpl v, vec3 p, vec3 nv, float h, out vec2 k) {
    vec3 a = abs(v.normal.xyz);
    vec3 ea = a.x >= a.y ? (a.x >= a.z ? vec3(1, 0, 0) : vec3(0, 0, 1)) : (a.y >= a.z ? vec3(0, 1, 0) : vec3(0, 0, 1));
    if (dot(a, ea) < AXIS_PLANE * length(v.normal.xyz)) return false;
    vec3 eb = ea.zxy, ec = ea.yzx;  // the plane's two axes
    vec3 lo = source_boxes[2 * j].xyz - 0.5 * h - p, hi = source_boxes[2 * j + 1].xyz + 0.5 * h - p;  // voxels' extent
    vec3 base = ea * (v.position.xyz - p);  // corners relative to the receiver, in order around the rectangle
    vec3 q0 = base + eb * lo + ec * lo, q1 = base + eb * hi + ec * lo;
    vec3 q2 = base + eb * hi + ec * hi, q3 = base + eb * lo + ec * hi;
    vec4 up = vec4(dot(q0, nv), dot(q1, nv), dot(q2, nv), dot(q3, nv));
    vec3 f0 = q0, f1 = q1, f2 = q2, f3 = q3;
    bool front = any(greaterThan(up, vec4(0.0))), back = any(lessThan(up, vec4(0.0)));
    if ((front && !clip_quad(f0, f1, f2, f3, up)) || (back && !clip_quad(q0, q1, q2, q3, -up))) return false;
    float area = dot(hi - lo, eb) * dot(hi - lo, ec);
    k = vec2(front ? quad_projected_solid_angle(f0, f1, f2, f3, nv) : 0.0,
             back ? quad_projected_solid_angle(q0, q1, q2, q3, -nv) : 0.0) / (PI * area);
    return true;
}
#endif

// What VPL j (v) of unit flux gives a receiver voxel at p (normal nv) per side: (front, back) irradiance per watt,
// so that E = Φ · kernel. Linear in Φ: the transfer (MODE_TRANSFER) stores it per receiver and source.
vec2 vpl_kernel(int j, Vpl v, vec3 p, vec3 nv, float h) {
    vec3 nl = v.normal.xyz;
    vec3 d = p - v.position.xyz;
    // Height above the VPL's plane: ≤ 0 behind it (no light); under half a voxel (its box's extent along the
    // normal), the voxel holds the VPL's own surface — or the other side of a slab thinner than a voxel — and
    // its centre is off the surface by up to half a voxel, which would light the back of a surface with its
    // own front (a roof's underside with its sunlit top): skip it too.
    float height = dot(nl, d);
    if (height < 0.5 * h * dot(abs(nl), vec3(1.0))) return vec2(0.0);
    float d2 = dot(d, d);
    float dist = sqrt(d2);
    vec3 w = d / dist;
    float receive = dot(nv, -w);  // > 0: the VPL is on the voxel's front side (as in lpv/absorb.glsl)
    float source_area = max(PI * h * h, v.normal.w);
    float t = transmittance(v.position.xyz, w, dist);
    if (t <= 0.0) return vec2(0.0);
    if (d2 > NEAR_FIELD * source_area / PI) {
        float e = height / dist * abs(receive) * t / (PI * d2 + source_area);
        return receive > 0.0 ? vec2(e, 0.0) : vec2(0.0, e);
    }
#if defined(MODE_TRANSFER)
    vec2 exact;
    if (rectangle_kernel(j, v, p, nv, h, exact)) return exact * t;
#endif
    // Near a cluster (within 3 of its disc radii) its centroid is a poor stand-in — at a corner the
    // centroid sits level with a receiver its nearer part faces: four quarter discs, at their centroids
    // (0.6 radii out along the diagonals), each with a quarter of the flux and area. Visibility: the centroid's.
    vec3 t1 = normalize(abs(nl.x) < 0.9 ? cross(nl, vec3(1.0, 0.0, 0.0)) : cross(nl, vec3(0.0, 1.0, 0.0)));
    vec3 t2 = cross(nl, t1);
    float r = 0.6 * 0.70710678 * sqrt(source_area / PI);
    vec2 k = vec2(0.0);
    for (int q = 0; q < 4; ++q) {
        vec3 ds = d - r * ((q & 1) == 0 ? t1 : -t1) - r * ((q & 2) == 0 ? t2 : -t2);
        float s2 = dot(ds, ds);
        vec3 ws = ds * inversesqrt(s2);
        float rs = dot(nv, -ws);
        float e = 0.25 * dot(nl, ws) * abs(rs) * t / (PI * s2 + 0.25 * source_area);
        if (rs > 0.0) k.x += e; else k.y += e;
    }
    return k;
}

void main() {
    if (int(gl_GlobalInvocationID.x) >= u_surface_count) return;
    ivec3 f = surfaces[gl_GlobalInvocationID.x].xyz;
    vec4 area = texelFetch(u_voxel_area, f, 0);
    vec3 nv = texelFetch(u_voxel_normal, f, 0).xyz;
    bool receives = area.a > 0.0 && dot(nv, nv) > 0.0;
    nv = receives ? normalize(nv) : vec3(0.0, 0.0, 1.0);
    float h = 0.5 * u_grid_cell;
    vec3 p = u_fine_origin + (vec3(f) + 0.5) * h;
#if defined(MODE_TRANSFER)
    // One row per source of this dispatch: transfer[(j − first) · surfaces + receiver] = (front, back).
    bool fresh_receiver = !u_update || surfaces[gl_GlobalInvocationID.x].w != 0;
    for (int j = u_vpl_first; j < u_vpl_first + u_vpl_count; ++j) {
        bool fresh = fresh_receiver || vpls[j].flux.w != 0.0 || crosses_box(vpls[j].position.xyz, p);
        transfer[(j - u_vpl_first) * u_surface_count + int(gl_GlobalInvocationID.x)] =
            !fresh ? vec2(uintBitsToFloat(0x7fc00000u)) : receives ? vpl_kernel(j, vpls[j], p, nv, h) : vec2(0.0);
    }
#else
    if (!receives) return;
    vec3 front = vec3(0.0), back = vec3(0.0);
    for (int j = u_vpl_first; j < u_vpl_first + u_vpl_count; ++j) {
        vec2 k = vpl_kernel(j, vpls[j], p, nv, h);
        front += vpls[j].flux.rgb * k.x;
        back += vpls[j].flux.rgb * k.y;
    }
    imageStore(u_front, f, vec4(imageLoad(u_front, f).rgb + front, 1.0));
    imageStore(u_back, f, vec4(imageLoad(u_back, f).rgb + back, 1.0));
    imageStore(u_front_total, f, vec4(imageLoad(u_front_total, f).rgb + front, 1.0));
    imageStore(u_back_total, f, vec4(imageLoad(u_back_total, f).rgb + back, 1.0));
#endif
}
