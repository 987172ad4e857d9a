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
#include "common/polygon.glsl"  // split_octagon_projected_solid_angles

layout(local_size_x = 64) in;
#include "common/structs.glsl"
layout(std430, binding = 6) readonly buffer VplList { Vpl vpls[]; };
layout(std430, binding = 7) readonly buffer SurfaceVoxels { ivec4 surfaces[]; };  // fine voxels with surfaces
uniform int u_surface_count;
uniform int u_vpl_first;           // this dispatch's VPLs: [first, first + count) (see lpv/gather.gather)
uniform int u_vpl_count;
uniform sampler3D u_voxel_normal;   // fine voxels: mean sign-canonical normal
uniform sampler3D u_voxel_area;     // fine voxels: rgb projected areas, a = surface area (m²)
uniform sampler3D u_coverage;       // LPV cells (lpv/crossings.py): their surfaces' plane(s) and covered fraction,
uniform sampler3D u_layers;         //   where those planes lie (cells), how near an end a crossing is its own,
uniform sampler3D u_layers_far;     //   and where a second layer lies, if any (packed: crossings._pack)
uniform bool u_occlusion;
uniform vec3 u_fine_origin;
uniform vec3 u_grid_origin;
uniform float u_grid_cell;
uniform ivec3 u_grid_size;
#if defined(MODE_TRANSFER)
layout(std430, binding = 8) writeonly buffer Transfer { vec2 transfer[]; };  // lpv/transfer.py
// The receivers (lpv/receivers.py): a voxel's surfaces of one dominant axis each, surfaces[i] its voxel and
// receivers[2i] its mean normal (xyz) and area (w), receivers[2i + 1] its surfaces' centroid.
layout(std430, binding = 10) readonly buffer Receivers { vec4 receivers[]; };
// Per source: the octagon its surfaces span in its plane (lpv/clusters.Clusters.polygon), eight corners in order;
// the first's w is 1 where the cluster is planar, the second's its area.
layout(std430, binding = 9) readonly buffer SourcePolygons { vec4 source_polygons[]; };
#if defined(PAIRS)
// An update after an edit (lpv/transfer.update_transfer): only the listed (source, receiver) pairs, one per
// invocation — on llvmpipe a branch runs for every lane whenever any lane takes it, so pairs skipped inside the loop
// over sources cost what evaluated ones do.
layout(std430, binding = 11) readonly buffer Pairs { ivec2 pairs[]; };
uniform int u_pair_first;
uniform int u_pair_count;
#endif
#else
layout(rgba32f, binding = 0) uniform image3D u_front;  // this bounce: rgb irradiance (W/m²), a = 1 if surface
layout(rgba32f, binding = 1) uniform image3D u_back;
layout(rgba32f, binding = 2) uniform image3D u_front_total;
layout(rgba32f, binding = 3) uniform image3D u_back_total;
#endif

const float PI = 3.14159265358979;


vec3 step01(vec3 d) {
    return vec3(greaterThan(d, vec3(0.0)));
}
const float OWN_PLANE = 0.1;  // MODE_TRANSFER: a receiver this near a source's plane (in fine voxels) lies in it
const float NEAR_FIELD = 9.0;  // (distance / disc radius)² below which a VPL is split in four
const float POLYGON_FIELD = 36.0;  // MODE_TRANSFER: within 6 disc radii, a planar cluster as its octagon
const float LAYER_END = 0.05;  // lpv/crossings.END_SLACK: a layer where its surfaces lie

// Which of the three axis planes' crossings at parameters tc lie in the box cell c's surfaces span, given as
// lpv/crossings.box_code (0: the whole cell); c, o, dir in cells. An axis plane covers its cell only there.
float in_span(vec3 q, vec3 lo, vec3 hi, vec3 along) {  // inside along the axes `along` selects
    vec3 outside = (vec3(lessThan(q, lo - 1e-3)) + vec3(greaterThan(q, hi + 1e-3))) * along;
    return float(all(equal(outside, vec3(0.0))));
}
vec3 in_box(float code, ivec3 c, vec3 o, vec3 dir, vec3 tc) {
    if (code < 1.0) return vec3(1.0);
    uint p = uint(code) - 1u;
    vec3 lo = vec3(c) + vec3(uvec3(p, p >> 4, p >> 8) & 15u) / 16.0;
    vec3 hi = vec3(c) + (vec3(uvec3(p >> 12, p >> 16, p >> 20) & 15u) + 1.0) / 16.0;
    return vec3(in_span(o + tc.x * dir, lo, hi, vec3(0, 1, 1)), in_span(o + tc.y * dir, lo, hi, vec3(1, 0, 1)),
                in_span(o + tc.z * dir, lo, hi, vec3(1, 1, 0)));  // no loop: see vpls_per_dispatch
}

// The crossings the ray o + s·dir, s in [t, t_exit) (span = (t, t_exit, len)), makes with planes along unit `n` at
// offsets `layer` (near, far) covering `coverage` — those beyond `ends` (source's, receiver's) of either end along
// n — summed.
float crossings_of(vec3 o, vec3 dir, vec3 span, vec3 n, vec2 layer, vec2 ends, vec2 coverage) {
    float facing = dot(n, dir);
    vec2 tc = (layer - dot(n, o)) / (facing != 0.0 ? facing : 1e-30);
    vec2 hit = vec2(greaterThanEqual(tc, vec2(span.x))) * vec2(lessThan(tc, vec2(span.y)))
             * vec2(greaterThan(abs(tc * facing), vec2(ends.x)))
             * vec2(greaterThan(abs((span.z - tc) * facing), vec2(ends.y)));
    return dot(coverage, hit);
}

// The same for the three axis planes at once, each with its own ends (no loop: see vpls_per_dispatch).
float axis_crossings(ivec3 c, vec3 o, vec3 dir, vec3 inv, vec3 span, vec3 layer, vec3 end_from, vec3 end_to,
                     vec4 coverage) {
    vec3 tc = (layer - o) * inv;  // where the ray meets each plane
    vec3 hit = vec3(greaterThanEqual(tc, vec3(span.x))) * vec3(lessThan(tc, vec3(span.y)))
             * vec3(greaterThan(abs(tc * dir), end_from)) * vec3(greaterThan(abs((span.z - tc) * dir), end_to));
    if (all(equal(hit, vec3(0.0)))) return 0.0;
    return dot(coverage.xyz, hit * in_box(coverage.w, c, o, dir, tc));
}

// A plane along n is an end's own only if that end's surface (normal `own`) lies along it too — within 60°: a floor
// beside a wall is not the wall, however near it.
#define OWN_FACING 0.5
float own_end(vec3 n, vec3 own, float end) {  // end > 1: where the surfaces lie is known (lpv/crossings._pack)
    return end <= 1.0 ? end : abs(dot(n, own)) >= OWN_FACING ? end - 1.0 : LAYER_END;
}
vec3 own_ends(vec3 own, vec3 end) {
    return mix(vec3(LAYER_END), end, vec3(greaterThanEqual(abs(own), vec3(OWN_FACING))));
}

// The ray parameters (cells) at which o + t·dir leaves cell c across each axis; never along an axis dir does not move
// on (1e30 × a fraction of a cell would be a huge negative parameter, and that axis stepped first for nothing).
vec3 cell_exit(ivec3 c, vec3 o, vec3 dir, vec3 inv) {
    return mix((vec3(c) + step01(dir) - o) * inv, vec3(1e30), equal(dir, vec3(0.0)));
}

// Visibility between a VPL at `from` (normal n_from) and a receiver (normal n_to) `dist` away along unit `dir`: the ray walks the LPV cells it passes
// (the traversal of Amanatides and Woo 1987) and, in each, meets the cell's surfaces only if it crosses the plane where
// they lie inside the cell, inside the box they span — one oblique plane, or one per axis where a floor meets a wall,
// each one layer or two (a pillar's faces; lpv/crossings.py) — then their covered fraction of the light is stopped,
// as the geometry volume stops it at a face in propagation. A ray passing a wall without crossing it is not dimmed (a
// trilinear density would, within a cell of every wall and corner). A crossing near enough an end along a plane facing
// the way that end's surface does (lpv/crossings.py: the layers' ends) is that end's own surface and is not counted.
float transmittance(vec3 from, vec3 n_from, vec3 dir, float dist, vec3 n_to) {
    if (!u_occlusion) return 1.0;
    vec3 o = (from - u_grid_origin) / u_grid_cell;  // in cells
    float len = dist / u_grid_cell;
    ivec3 c = ivec3(floor(o));
    ivec3 step = ivec3(sign(dir));
    vec3 inv = vec3(dir.x != 0.0 ? 1.0 / dir.x : 1e30, dir.y != 0.0 ? 1.0 / dir.y : 1e30,
                    dir.z != 0.0 ? 1.0 / dir.z : 1e30);
    vec3 t_max = cell_exit(c, o, dir, inv);
    float t = 0.0, crossings = 0.0;
    int cells = u_grid_size.x + u_grid_size.y + u_grid_size.z + 3;  // a straight line visits no more
    for (int k = 0; k < cells && t < len; ++k) {
        float t_exit = min(t_max.x, min(t_max.y, t_max.z));
        if (all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, u_grid_size))) {
            vec4 coverage = texelFetch(u_coverage, c, 0);
            vec3 span = vec3(t, min(t_exit, len), len);  // the segment ends at the receiver
            if (coverage.w < 0.0) {  // one plane: normal coverage.xyz covering −coverage.w, layers (far, end, far's, near)
                vec4 l = texelFetch(u_layers, c, 0);  // end < 0: a second layer
                vec2 ends = vec2(own_end(coverage.xyz, n_from, abs(l.y)), own_end(coverage.xyz, n_to, abs(l.y)));
                crossings += crossings_of(o, dir, span, coverage.xyz, l.wx, ends, vec2(-coverage.w, l.y < 0.0 ? l.z : 0.0));
            } else if (any(greaterThan(coverage.xyz, vec3(0.0)))) {  // axis planes: layers (near x, y, z, end)
                vec4 l = texelFetch(u_layers, c, 0);  // end < 0: a second layer along some axis, at layers_far
                vec3 far = l.w < 0.0 ? texelFetch(u_layers_far, c, 0).xyz : l.xyz;
                vec3 two = vec3(notEqual(far, l.xyz));  // the far layer equals the near one along the other axes
                bool planes = abs(l.w) > 1.0;  // meeting planes (a floor and a wall), not a curve: lpv/crossings._pack
                vec3 end = mix(vec3(planes ? abs(l.w) - 1.0 : abs(l.w)), vec3(LAYER_END), two);
                vec3 end_from = planes ? own_ends(n_from, end) : end, end_to = planes ? own_ends(n_to, end) : end;
                crossings += axis_crossings(c, o, dir, inv, span, l.xyz, end_from, end_to, coverage)
                           + (l.w < 0.0 ? axis_crossings(c, o, dir, inv, span, far, end_from, end_to,
                                                         vec4(coverage.xyz * two, coverage.w)) : 0.0);
            }
            if (crossings >= 1.0) return 0.0;
            if (coverage.w >= 2.0 && coverage.xyz == vec3(0.0)) {  // empty, and so is every cell within w − 1
                // (lpv/crossings.mark_empty_space): the ray moves at most w − 1 cells along any axis over that
                // length, so it meets no surface there; go on from the cell it reaches (proximity clouds:
                // Cohen and Sheffer 1994)
                t += coverage.w - 1.0;
                if (t >= len) break;
                c = ivec3(floor(o + dir * t));
                t_max = cell_exit(c, o, dir, inv);
                continue;
            }
        }
        int axis = t_max.x <= t_max.y ? (t_max.x <= t_max.z ? 0 : 2) : (t_max.y <= t_max.z ? 1 : 2);
        c[axis] += step[axis];
        t_max = cell_exit(c, o, dir, inv);  // not accumulated: a layer on a cell's face (a wall on the grid) is
        t = t_exit;                         // met at exactly the parameter its crossing test computes
    }
    return 1.0 - crossings;
}

#if defined(MODE_TRANSFER)
// Near a cluster that lies in a plane (a wall's, a floor's, at any angle): the exact irradiance per watt of a
// Lambertian octagon of uniform radiance Φ/(π·A) spanning its surfaces in that plane (lpv/clusters.polygons: a
// rectangle where they fill one, a block of floor cut off by a wall at an angle otherwise) — Lambert's formula over
// the edges of the part above each side of the receiver's plane (common/polygon.glsl). A receiver beside a wall's
// edge gets half its irradiance from the floor right next to it; the quarter discs below, 1–2 cells out, gave edges
// 0.7–0.9 of it in a closed box. False for a cluster whose surfaces bend (w = 0).
bool polygon_kernel(int j, vec3 p, vec3 nv, out vec2 k) {
    vec4 first = source_polygons[8 * j];
    if (first.w == 0.0) return false;
    vec3 q0 = first.xyz - p, q1 = source_polygons[8 * j + 1].xyz - p, q2 = source_polygons[8 * j + 2].xyz - p;
    vec3 q3 = source_polygons[8 * j + 3].xyz - p, q4 = source_polygons[8 * j + 4].xyz - p;
    vec3 q5 = source_polygons[8 * j + 5].xyz - p, q6 = source_polygons[8 * j + 6].xyz - p;
    vec3 q7 = source_polygons[8 * j + 7].xyz - p;
    k = split_octagon_projected_solid_angles(q0, q1, q2, q3, q4, q5, q6, q7, nv)
      / (PI * source_polygons[8 * j + 1].w);
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
#if defined(MODE_TRANSFER)
    // Receivers and clusters sit where their surfaces lie (lpv/receivers.py), so a receiver across the source's
    // plane (a floor beside a wall) is lit from OWN_PLANE of a fine voxel above it — but one facing the source's way
    // (a neighbouring patch of a sphere, a slab's far face merged into one voxel with its near one) still lies in the
    // source's own surface within the old half voxel, scaled by how parallel the two are: without that, a metal
    // sphere's patches lit each other (metals' Diffuse Indirect 1.16× Cycles').
    if (height < h * max(OWN_PLANE, 0.5 * dot(abs(nl), vec3(1.0)) * abs(dot(nl, nv)))) return vec2(0.0);
#else
    if (height < 0.5 * h * dot(abs(nl), vec3(1.0))) return vec2(0.0);
#endif
    float d2 = dot(d, d);
    float dist = sqrt(d2);
    vec3 w = d / dist;
    float receive = dot(nv, -w);  // > 0: the VPL is on the voxel's front side (as in lpv/absorb.glsl)
    float source_area = max(PI * h * h, v.normal.w);
    float t = transmittance(v.position.xyz, nl, w, dist, nv);
    if (t <= 0.0) return vec2(0.0);
#if defined(MODE_TRANSFER)
    vec2 exact;
    if (d2 <= POLYGON_FIELD * source_area / PI && polygon_kernel(j, p, nv, exact)) return exact * t;
#endif
    if (d2 > NEAR_FIELD * source_area / PI) {
        float e = height / dist * abs(receive) * t / (PI * d2 + source_area);
        return receive > 0.0 ? vec2(e, 0.0) : vec2(0.0, e);
    }
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

#if defined(MODE_TRANSFER)
// What source j of unit flux gives receiver i (lpv/receivers.py: receivers[2i] its mean normal and area,
// receivers[2i + 1] its surfaces' centroid), per side.
vec2 receiver_kernel(int j, int i) {
    vec4 oriented = receivers[2 * i];
    vec3 nv = oriented.xyz;
    if (!(oriented.w > 0.0 && dot(nv, nv) > 0.0)) return vec2(0.0);
    return vpl_kernel(j, vpls[j], receivers[2 * i + 1].xyz, normalize(nv), 0.5 * u_grid_cell);
}

#if defined(PAIRS)
void main() {  // transfer[k] = pair k's (front, back)
    int k = int(gl_GlobalInvocationID.x);
    if (k >= u_pair_count) return;
    ivec2 pair = pairs[u_pair_first + k];
    transfer[k] = receiver_kernel(pair.x, pair.y);
}
#else
void main() {  // one row per source of this dispatch: transfer[(j − first) · surfaces + receiver] = (front, back)
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_surface_count) return;
    for (int j = u_vpl_first; j < u_vpl_first + u_vpl_count; ++j)
        transfer[(j - u_vpl_first) * u_surface_count + i] = receiver_kernel(j, i);
}
#endif
#else
void main() {
    if (int(gl_GlobalInvocationID.x) >= u_surface_count) return;
    ivec3 f = surfaces[gl_GlobalInvocationID.x].xyz;
    vec4 area = texelFetch(u_voxel_area, f, 0);
    vec3 nv = texelFetch(u_voxel_normal, f, 0).xyz;
    if (!(area.a > 0.0 && dot(nv, nv) > 0.0)) return;
    nv = normalize(nv);
    float h = 0.5 * u_grid_cell;
    vec3 p = u_fine_origin + (vec3(f) + 0.5) * h;
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
}
#endif
