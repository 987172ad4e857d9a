// SPDX-License-Identifier: GPL-3.0-or-later
// Rasterisation-based surface voxelisation (Freed 2018, §4.1.1, after Crassin and Green 2012).
//
// Geometry shader: project each triangle along the dominant axis of its normal (Algorithm 1) onto a plane
// rasterised at `u_supersample` pixels per voxel, and make coverage conservative by drawing, instead of the
// triangle, whichever is smaller of (a) the triangle with each edge pushed out by half a pixel diagonal
// (the "dilation in a geometry shader" alternative of Freed's §4.1.1, Hasselgren et al. 2005) and (b) its pixel
// bounding box.
// Either contains the centre of every pixel the triangle touches, so thin or tiny triangles still get fragments.
//
// Fragment shader: clip the *original* triangle exactly to the fragment's pixel square and then to each
// voxel slab it crosses along the dominant axis (the depth is an exact plane over the pixel — the analytic form
// of "depth + depth derivatives"), and deposit each piece's exact area. Every voxel the surface crosses gets
// exactly the area of the surface inside it, so areas sum to the triangle's area however coarse the pixels;
// `u_supersample` only sets how densely textures are sampled (one albedo sample per piece, at its centroid).
//
// Covered surfaces (SIDES, after a MODE_FRONT pass): a piece with another one wholly in front of it in the same
// pixel column and voxel (a rug lying 1 mm above a floor, a poster on a wall) is hidden from that side, so its
// albedo is left out of that side's mean (voxel/common.glsl deposit_seen): the side sees the rug, the floor's
// underside the floor. MODE_FRONT keeps, per pixel column, voxel layer and side of the dominant axis, the largest
// nearest-depth of a piece along that side; a piece is covered on a side when even its farthest point there lies
// behind that. Pieces of one continuous surface touch along their shared edges, so they never cover each other.
#if defined(VERTEX_SHADER)
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;
uniform vec3 u_grid_origin;       // grid min corner (world)
uniform float u_inv_cell;    // 1 / cell size
out vec3 v_grid;
out vec2 v_uv;
void main() {
    v_grid = (in_position - u_grid_origin) * u_inv_cell;   // grid units: voxel (i,j,k) = [i,i+1)×[j,j+1)×[k,k+1)
    v_uv = in_uv;
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
#endif

#if defined(GEOMETRY_SHADER)
layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;
in vec3 v_grid[];
in vec2 v_uv[];
uniform float u_supersample;    // pixels per voxel along each axis
uniform vec2 u_viewport;        // framebuffer size in pixels
uniform float u_dilation;       // half-pixel plus a margin for the rasteriser's subpixel snapping
uniform int u_axis_only;        // ≥ 0: only the triangles whose dominant axis this is (voxelize axis_only)
flat out vec2 g_p[3];           // the undilated triangle in pixel units of the dominant plane
flat out vec2 g_uv[3];
flat out vec3 g_normal;         // unit geometric normal (grid space = world directions)
flat out vec3 g_depth;          // (depth at g_p[0], d depth/d px.x, d depth/d px.y), depth in grid units
flat out float g_area_per_px;   // cell² of surface per pixel² of projection = 1 / (ss² |n_dominant|)
flat out int g_axis;            // dominant axis: 0 x, 1 y, 2 z

// Plane coordinates for a dominant axis, cyclic so the frame stays right-handed: (u, v, depth).
vec3 to_plane(vec3 p, int axis) { return axis == 0 ? p.yzx : (axis == 1 ? p.zxy : p); }

void emit(vec2 q) {
    gl_Position = vec4(q / u_viewport * 2.0 - 1.0, 0.0, 1.0);
    EmitVertex();
}

float cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

void main() {
    vec3 n = cross(v_grid[1] - v_grid[0], v_grid[2] - v_grid[0]);
    float len = length(n);
    if (!(len > 0.0)) return;   // degenerate: no area to deposit
    n /= len;
    vec3 an = abs(n);
    int axis = (an.x >= an.y && an.x >= an.z) ? 0 : (an.y >= an.z ? 1 : 2);
    if (u_axis_only >= 0 && axis != u_axis_only) return;
    vec3 np = to_plane(n, axis);
    vec2 q[3];
    for (int i = 0; i < 3; ++i) q[i] = to_plane(v_grid[i], axis).xy * u_supersample;
    // depth(px) = depth0 + a·(px.x − q0.x) + b·(px.y − q0.y), from n·(p − p0) = 0 in grid units
    vec3 depth = vec3(to_plane(v_grid[0], axis).z, -np.x / (np.z * u_supersample), -np.y / (np.z * u_supersample));

    // (a) Dilated triangle: offset every edge line outward by h·(|m.x| + |m.y|) (the distance to the farthest
    // corner of a half-size-h square) and intersect neighbouring offset lines.
    float orient = sign(cross2(q[1] - q[0], q[2] - q[0]));
    float h = u_dilation;
    vec2 m[3];
    float d[3];
    for (int i = 0; i < 3; ++i) {
        vec2 e = q[(i + 1) % 3] - q[i];
        m[i] = normalize(vec2(e.y, -e.x) * orient);      // outward unit normal of edge i (q[i] → q[i+1])
        d[i] = h * (abs(m[i].x) + abs(m[i].y));
    }
    vec2 dil[3];
    bool ok = orient != 0.0;
    for (int i = 0; i < 3; ++i) {
        vec2 a = m[(i + 2) % 3], b = m[i];                // edges meeting at vertex i
        float det = cross2(a, b);
        ok = ok && abs(det) > 1e-4;
        vec2 delta = vec2(d[(i + 2) % 3] * b.y - d[i] * a.y, a.x * d[i] - b.x * d[(i + 2) % 3]) / det;
        dil[i] = q[i] + delta;
    }
    vec2 lo = min(min(q[0], q[1]), q[2]) - h, hi = max(max(q[0], q[1]), q[2]) + h;
    float box_area = (hi.x - lo.x) * (hi.y - lo.y);
    float dil_area = abs(cross2(dil[1] - dil[0], dil[2] - dil[0])) * 0.5;
    ok = ok && dil_area < box_area;                       // also false for NaN/inf from a near-degenerate corner

    for (int k = 0; k < (ok ? 3 : 4); ++k) {
        for (int i = 0; i < 3; ++i) { g_p[i] = q[i]; g_uv[i] = v_uv[i]; }
        g_normal = n;
        g_depth = depth;
        g_area_per_px = 1.0 / (u_supersample * u_supersample * abs(np.z));
        g_axis = axis;
        // (b) the bounding box as a strip: lo, (hi.x, lo.y), (lo.x, hi.y), hi
        emit(ok ? dil[k] : vec2((k & 1) == 1 ? hi.x : lo.x, (k & 2) == 2 ? hi.y : lo.y));
    }
    EndPrimitive();
}
#endif

#if defined(FRAGMENT_SHADER)
#include "voxel/common.glsl"
uniform int u_supersample_i;
flat in vec2 g_p[3];
flat in vec2 g_uv[3];
flat in vec3 g_normal;
flat in vec3 g_depth;
flat in float g_area_per_px;
flat in int g_axis;

#define MAXV 10   // a triangle clipped by a square has ≤ 7 vertices, then ≤ 2 slab planes add one each

// Sutherland–Hodgman: keep the part of polygon p (n vertices) where dot(plane, (x, y, 1)) ≥ 0.
int clip(inout vec2 p[MAXV], int n, vec3 plane) {
    vec2 o[MAXV];
    int m = 0;
    for (int i = 0; i < n; ++i) {
        vec2 a = p[i], b = p[(i + 1) % n];
        float fa = dot(plane, vec3(a, 1.0)), fb = dot(plane, vec3(b, 1.0));
        if (fa >= 0.0) o[m++] = a;
        if ((fa >= 0.0) != (fb >= 0.0)) o[m++] = a + (b - a) * (fa / (fa - fb));
    }
    for (int i = 0; i < m; ++i) p[i] = o[i];
    return m;
}

// Area (≥ 0) and area centroid of a polygon (shoelace).
float poly_area(vec2 p[MAXV], int n, out vec2 center) {
    float a2 = 0.0;
    vec2 c = vec2(0.0);
    for (int i = 0; i < n; ++i) {
        vec2 a = p[i], b = p[(i + 1) % n];
        float w = a.x * b.y - a.y * b.x;
        a2 += w;
        c += (a + b) * w;
    }
    center = abs(a2) > 0.0 ? c / (3.0 * a2) : p[0];
    return abs(a2) * 0.5;
}

// Voxel (u, v, depth) in the dominant plane's frame → grid (x, y, z); inverse of to_plane.
ivec3 from_plane(ivec3 c, int axis) { return axis == 0 ? c.zxy : (axis == 1 ? c.yzx : c); }
vec3 from_plane(vec3 c, int axis) { return axis == 0 ? c.zxy : (axis == 1 ? c.yzx : c); }

#if defined(MODE_FRONT) || defined(SIDES)
// Per pixel column, dominant axis a and voxel layer k along it: layer offset(a) + 2k the largest nearest-depth
// (along +a) of a piece, offset(a) + 2k + 1 the largest (1 − farthest depth), in 1/65535 of a cell: larger =
// further out along that side. The three axes' layers share one image (offsets 0, 2·nx, 2·(nx + ny)).
layout(binding = 6, r32ui) coherent uniform uimage3D u_front;
#define FRONT_TOLERANCE 66u   // 1/1000 of a cell: coplanar pieces (duplicates) all count

uint to_front(float f) { return uint(clamp(f, 0.0, 1.0) * 65535.0 + 0.5); }

ivec3 front_texel(int k, int side) {
    int offset = g_axis == 0 ? 0 : 2 * (g_axis == 1 ? u_grid_size.x : u_grid_size.x + u_grid_size.y);
    return ivec3(ivec2(gl_FragCoord.xy), offset + 2 * k + side);
}

uint front_load(ivec3 t) { return imageLoad(u_front, t).r; }

void front_max(ivec3 t, uint d) { imageAtomicMax(u_front, t, d); }
#endif

void main() {
    vec2 pix = floor(gl_FragCoord.xy);                     // pixel's min corner, in pixels
    ivec2 col = ivec2(pix) / u_supersample_i;             // voxel column in the dominant plane
    ivec3 size_p = g_axis == 0 ? u_grid_size.yzx : (g_axis == 1 ? u_grid_size.zxy : u_grid_size);
    if (any(greaterThanEqual(col, size_p.xy))) return;

    // Triangle in coordinates local to the pixel square [0,1]², then clipped to it.
    vec2 p[MAXV];
    for (int i = 0; i < 3; ++i) p[i] = g_p[i] - pix;
    int n = 3;
    n = clip(p, n, vec3(1.0, 0.0, 0.0));
    n = clip(p, n, vec3(-1.0, 0.0, 1.0));
    n = clip(p, n, vec3(0.0, 1.0, 0.0));
    n = clip(p, n, vec3(0.0, -1.0, 1.0));
    if (n < 3) return;

    // Depth over the pixel: depth(x, y) = dc + a·x + b·y in local coordinates.
    float dc = g_depth.x + g_depth.y * (pix.x - g_p[0].x) + g_depth.z * (pix.y - g_p[0].y);
    float dmin = 1e30, dmax = -1e30;
    for (int i = 0; i < n; ++i) {
        float dv = dc + g_depth.y * p[i].x + g_depth.z * p[i].y;
        dmin = min(dmin, dv);
        dmax = max(dmax, dv);
    }
    int k0 = max(int(floor(dmin)), 0), k1 = min(int(floor(dmax)), size_p.z - 1);

    // Barycentric frame of the original triangle, for UVs at piece centroids.
    vec2 e1 = g_p[1] - g_p[0], e2 = g_p[2] - g_p[0];
    float inv_det = 1.0 / (e1.x * e2.y - e1.y * e2.x);
    for (int k = k0; k <= k1; ++k) {
        vec2 s[MAXV];
        for (int i = 0; i < n; ++i) s[i] = p[i];
        int m = n;
        if (dmin < float(k)) m = clip(s, m, vec3(g_depth.y, g_depth.z, dc - float(k)));          // depth ≥ k
        if (dmax > float(k + 1)) m = clip(s, m, vec3(-g_depth.y, -g_depth.z, float(k + 1) - dc)); // depth ≤ k+1
        if (m < 3) continue;
#if defined(MODE_FRONT) || defined(SIDES)
        float f_lo = 1.0, f_hi = 0.0;  // the piece's depth range within voxel layer k
        for (int i = 0; i < m; ++i) {
            float f = dc + g_depth.y * s[i].x + g_depth.z * s[i].y - float(k);
            f_lo = min(f_lo, f);
            f_hi = max(f_hi, f);
        }
#endif
#if defined(MODE_FRONT)
        front_max(front_texel(k, 0), to_front(f_lo));
        front_max(front_texel(k, 1), to_front(1.0 - f_hi));
        continue;
#endif
        vec2 center;
        float area_px = poly_area(s, m, center);
        vec2 r = center + pix - g_p[0];
        float b1 = (r.x * e2.y - r.y * e2.x) * inv_det, b2 = (e1.x * r.y - e1.y * r.x) * inv_det;
        vec2 uv = g_uv[0] + (g_uv[1] - g_uv[0]) * b1 + (g_uv[2] - g_uv[0]) * b2;
        bvec2 seen = bvec2(true);
#if defined(SIDES)
        // The canonical normal points along +axis of the dominant axis: side 0 is the voxel's front.
        seen = bvec2(to_front(f_hi) + FRONT_TOLERANCE >= front_load(front_texel(k, 0)),
                     to_front(1.0 - f_lo) + FRONT_TOLERANCE >= front_load(front_texel(k, 1)));
#endif
        // The piece's centroid and box in the plane frame (pixels / supersample = cells; depth in cells) → the
        // voxel's frame.
        float ss = float(u_supersample_i);
        vec3 at = vec3((center + pix) / ss, dc + g_depth.y * center.x + g_depth.z * center.y);
        vec3 lo = vec3(1e30), hi = vec3(-1e30);
        for (int i = 0; i < m; ++i) {
            vec3 q = vec3((s[i] + pix) / ss, dc + g_depth.y * s[i].x + g_depth.z * s[i].y);
            lo = min(lo, q);
            hi = max(hi, q);
        }
        ivec3 voxel = from_plane(ivec3(col, k), g_axis);
        vec3 corner = vec3(voxel);
        deposit_seen(voxel, area_px * g_area_per_px, g_normal, voxel_albedo(uv), seen,
                     from_plane(at, g_axis) - corner, from_plane(lo, g_axis) - corner, from_plane(hi, g_axis) - corner);
    }
}
#endif
