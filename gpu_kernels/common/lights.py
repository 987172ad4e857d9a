# SPDX-License-Identifier: GPL-3.0-or-later
"""Lights → GPU records, and the shadow views every light needs (pure numpy; no GL here).

Units follow Cycles (docs/conventions.md; intern/cycles/scene/light.cpp):
- sun: `power` is irradiance at normal incidence (W/m²);
- point/spot: radiant intensity P/(4π) W/sr; a spot is a point light masked by its cone, not concentrated into it;
- area: one-sided Lambertian emitter of radiance P/(π·A) over its area A;
- emissive triangles: radiance = material emission (colour × strength), emitted from both sides as in Cycles;
- the world: a constant radiance L from every direction, a light as in Cycles (its light is Diffuse/Glossy Direct).
Area lights and emissive triangles are "polygon lights", integrated exactly (Lambert's polygon formula) in the shader,
shadowed by a few sample points on the light, each with a six-view shadow cube (the documented approximation).
Emissive triangles are grouped into a bounded number of clusters (common/emitters.py), each one polygon light whose
polygon is a list of triangles with their own radiance, shadowed from its own sample points on both sides of the
surface: every emissive triangle is shadowed, and the shadow cubes stay within ShadowSettings.emissive_sample_budget.
The world is one "sky light" shadowed from a fixed set of directions spread evenly over the sphere, one
orthographic shadow map each (`sky_directions`): its visibility at a point is the cosine-weighted share of those
directions that reach the sky. The maps hold the scene's real triangles, so a wall of any thickness, one-sided or
not, keeps the sky out of a closed room and only its openings let it in.

Every numpy dtype here mirrors a GLSL struct in shaders/common/lights.glsl field for field (std430).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import camera as cam
from . import emitters as em
from ..scene import Light, Scene, hash_parts

LIGHT_SUN, LIGHT_POINT, LIGHT_SPOT, LIGHT_POLYGON, LIGHT_SKY = 0, 1, 2, 3, 4
# VCT's voxel injection (vct/inject.py) shadows the sky from every SKY_INJECTION_STRIDE-th direction, pixels from all:
# the subset still spans the sphere (its cosine integral within 1-2%), the visibility is a ratio of weighted sums
# (exact where the sky is unoccluded), and a voxel's light is averaged and bounced before a pixel shows it.
SKY_INJECTION_STRIDE = 4

LIGHT_DTYPE = np.dtype([("color_type", "<f4", 4), ("position", "<f4", 4), ("direction", "<f4", 4),
                        ("params", "<f4", 4), ("polygon", "<f4", 4)])
VIEW_DTYPE = np.dtype([("view_projection", "<f4", (4, 4)), ("tile", "<f4", 4), ("origin", "<f4", 4),
                       ("info", "<f4", 4), ("emitter", "<f4", 4)])
DISK_SEGMENTS = 32
CUBE_DIRECTIONS = [(np.array(f), np.array(u)) for f, u in (
    ((1, 0, 0), (0, -1, 0)), ((-1, 0, 0), (0, -1, 0)), ((0, 1, 0), (0, 0, 1)),
    ((0, -1, 0), (0, 0, -1)), ((0, 0, 1), (0, -1, 0)), ((0, 0, -1), (0, -1, 0)))]


@dataclass
class ShadowSettings:
    sun_resolution: int = 2048
    spot_resolution: int = 1024
    cube_resolution: int = 512  # per face, point lights
    area_cube_resolution: int = 384  # per face at an area light's sample points (its soft shadows are read there)
    sample_cube_resolution: int = 256  # per face at an emitter's sample points, at most (emitter_cube_resolution)
    area_samples: int = 2  # n×n shadow sample points on square/rectangle lights (n² ring points on disks)
    emissive_sample_budget: int = 256  # cubes for all emitters: ≤ budget/2 clusters (common/emitters.py)
    emissive_texels: int = 64 * 6 * 256 ** 2  # all emitter cubes' texels: more cubes get smaller faces
    pcf_radius: int = 1  # PCF kernel (2r+1)²
    # The world's light: shadow directions over the sphere (0: unshadowed; a quadrature, its bands smoothed by
    # direct/sky_filter.glsl) and texels per side of each one's map (benchmarks/results/llvmpipe/sky.md: the sweep).
    sky_directions: int = 576
    sky_resolution: int = 224


@dataclass
class ShadowView:
    view_projection: np.ndarray  # (4, 4) float64, world → clip
    origin: np.ndarray  # eye (perspective) or a point on the sun's near plane
    ortho: bool
    texel_world: float  # world size of one texel at unit distance (perspective) or absolute (ortho)
    resolution: int
    far: float = 0.0  # perspective: depth is stored as distance / far; 0 for orthographic
    view_matrix: np.ndarray | None = None  # world → view (rows: right, up, −forward)
    half_extent: float = 0.0  # tan(half fov) (perspective) or half width in metres (orthographic)
    # Polygon lights' sample points: the normal the light emits along there and the share of the light's area the
    # point stands for (the weights of direct/eval.glsl's polygon_visibility); zero for other lights.
    emit_normal: np.ndarray | None = None
    emit_share: float = 0.0
    pcf_radius: int | None = None  # this view's PCF radius, where not ShadowSettings.pcf_radius (the sky's: 0)
    own_extent: float = 0.0  # tan(half angle) a cube face covers alone (1; lpv/inject.glsl cube_share), else 0
    unlit: bool = False  # sees only directions its light does not emit into: drawn into no atlas (cube_views)


@dataclass
class LightBuffers:
    lights: np.ndarray  # LIGHT_DTYPE records
    views: list  # ShadowView, in the order lights refer to them
    polygon_vertices: np.ndarray  # (V, 4) float32
    warnings: list
    view_lights: list = None  # index of the light record each view belongs to
    skipped: list = None  # lights left out because they cannot light the scene, in words (skipped_work)


def _color(light: Light) -> np.ndarray:
    # Cycles ignores the EEVEE-only diffuse_factor/specular_factor, so do we.
    return np.asarray(light.color, np.float64)[:3]


def _falloff_radius2(light: Light) -> float:
    """r² added to d² in the point-light law: Cycles' soft-falloff light is a disk of radius r facing the
    receiver, whose irradiance is P/(4π)·cosθ/(d²+r²) (kernel/light/point.h); a sphere light (soft falloff off)
    gives exactly the point law outside the sphere."""
    return light.radius ** 2 if light.soft_falloff else 0.0


def area_polygon(light: Light) -> tuple[np.ndarray, float]:
    """World-space polygon of an area light and its true area. Disks/ellipses become a 32-gon of equal area."""
    m = np.asarray(light.matrix_world, np.float64)
    sx = light.size
    sy = light.size if light.shape in ("SQUARE", "DISK") else light.size_y
    if light.shape in ("SQUARE", "RECTANGLE"):
        local = np.array([[-sx / 2, -sy / 2], [sx / 2, -sy / 2], [sx / 2, sy / 2], [-sx / 2, sy / 2]])
        area = sx * sy
    else:
        n = DISK_SEGMENTS
        # Scale the n-gon so its area equals the ellipse's π·a·b (the inscribed n-gon is smaller by sin(2π/n)·n/2π).
        k = math.sqrt(2 * math.pi / (n * math.sin(2 * math.pi / n)))
        t = np.arange(n) * 2 * math.pi / n
        local = np.stack([np.cos(t) * sx / 2 * k, np.sin(t) * sy / 2 * k], axis=1)
        area = math.pi * sx * sy / 4
    pts = np.concatenate([local, np.zeros((len(local), 1)), np.ones((len(local), 1))], axis=1) @ m.T
    # The matrix may scale the light (Blender scales area lights by the object scale).
    sx_w, sy_w = np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])
    return pts[:, :3], area * sx_w * sy_w


def area_sample_points(light: Light, n: int) -> np.ndarray:
    """n×n stratified points on a rectangle (cell centres), or n² points on rings of a disk, in world space."""
    m = np.asarray(light.matrix_world, np.float64)
    sx = light.size
    sy = light.size if light.shape in ("SQUARE", "DISK") else light.size_y
    if light.shape in ("SQUARE", "RECTANGLE"):
        g = (np.arange(n) + 0.5) / n - 0.5
        u, v = np.meshgrid(g * sx, g * sy)
        local = np.stack([u.ravel(), v.ravel()], axis=1)
    else:
        count = n * n
        if count == 1:
            local = np.zeros((1, 2))
        else:  # equal-area points: radius sqrt((i+0.5)/count), golden-angle spiral
            i = np.arange(count)
            r = np.sqrt((i + 0.5) / count)
            t = i * math.pi * (3 - math.sqrt(5))
            local = np.stack([r * np.cos(t) * sx / 2, r * np.sin(t) * sy / 2], axis=1)
    pts = np.concatenate([local, np.zeros((len(local), 1)), np.ones((len(local), 1))], axis=1) @ m.T
    return pts[:, :3]


def _scene_radius(scene: Scene) -> tuple[np.ndarray, float]:
    lo, hi = scene.bounds()
    centre = (lo + hi) / 2
    # A floor relative to where the scene is (a point-sized scene still gets a non-empty view), never in metres:
    # a scene scaled by s must get views scaled by s.
    # (1e-12 m, nine orders below the smallest scale the stress suite renders, only for a scene that is one point at
    # the origin.)
    floor = max(1e-6 * float(np.abs(centre).max()), 1e-12)
    return centre, max(float(np.linalg.norm(hi - lo)) / 2, floor)


def cube_views(origin, resolution: int, near: float, far: float, emit_normal=None, emit_share: float = 0.0,
               one_sided: bool = False) -> list[ShadowView]:
    """Six perspective views around `origin`, each a little wider than 90° so PCF never reads past a face edge.
    A polygon light's sample point passes the normal it emits along and the share of the light it stands for; a
    `one_sided` one (an area light) marks unlit the faces whose every direction lies behind it (d · normal ≤ 0):
    a point such a face would shadow gets none of the light, so the face is neither drawn nor read."""
    margin = 1.0 + 4.0 * 2 / resolution  # two texels of margin on each side
    proj = cam.perspective(2 * math.atan(margin), 1.0, near, far)
    views = []
    for fwd, up in CUBE_DIRECTIONS:
        view = cam.look_at(origin, np.asarray(origin) + fwd, up)
        n = view[:3, :3] @ np.asarray(emit_normal, np.float64) if one_sided else None  # (right, up, back) · normal
        views.append(ShadowView(proj @ view, np.asarray(origin, np.float64), False, 2 * margin / resolution,
                                resolution, far, view, margin, emit_normal, emit_share, own_extent=1.0,
                                unlit=one_sided and -n[2] + margin * (abs(n[0]) + abs(n[1])) <= 0.0))
    return views


def ortho_view(scene: Scene, d, resolution: int) -> ShadowView:
    """Orthographic view looking along unit direction d (where the light travels), fitted to the scene's bounding
    sphere."""
    centre, radius = _scene_radius(scene)
    d = np.asarray(d, np.float64)
    eye = centre - d * radius * 2
    up = np.array([0, 0, 1.0]) if abs(d[2]) < 0.99 else np.array([0, 1.0, 0])
    view = cam.look_at(eye, centre, up)
    r = radius * 1.02
    proj = cam.ortho(-r, r, -r, r, radius * 0.5, radius * 3.5)
    return ShadowView(proj @ view, eye, True, 2 * r / resolution, resolution, 0.0, view, r)


def spot_view(scene: Scene, light: Light, resolution: int, near: float, far: float) -> ShadowView:
    fov = min(light.spot_size * 1.05 + 4 * 2 / resolution, math.radians(170))
    pos = light.position
    d = light.direction
    up = np.array([0, 0, 1.0]) if abs(d[2]) < 0.99 else np.array([0, 1.0, 0])
    view = cam.look_at(pos, pos + d, up)
    return ShadowView(cam.perspective(fov, 1.0, near, far) @ view, pos, False,
                      2 * math.tan(fov / 2) / resolution, resolution, far, view, math.tan(fov / 2))


# Far planes rounded up to a power of FAR_STEP: an object moved at the scene's edge grows its bounds a little, and
# far planes that followed changed every lamp's views, so every map and RSM was drawn again (maps hold distance / far).
FAR_STEP = 2.0 ** 0.125


def _near_far(scene: Scene, origin) -> tuple[float, float]:
    centre, radius = _scene_radius(scene)
    far = FAR_STEP ** math.ceil(math.log(float(np.linalg.norm(np.asarray(origin) - centre)) + radius * 1.01, FAR_STEP))
    return far * 1e-4, far  # relative only: a metre-valued floor here clipped millimetre scenes' shadow maps


class _Records:
    """The light records, shadow views and polygon vertices being packed, in the order the shaders read them."""

    def __init__(self):
        self.records, self.views, self.polys, self.warnings, self.view_lights, self.skipped = [], [], [], [], [], []

    def add(self, type_, color, position=(0, 0, 0), radius=0.0, direction=(0, 0, -1), cos_half=0.0, smooth=0.0,
            light_views=(), samples=0, per=0, poly=None, two_sided=False):
        rec = np.zeros((), LIGHT_DTYPE)
        rec["color_type"] = (*color, type_)
        rec["position"] = (*position, radius)
        rec["direction"] = (*direction, cos_half)
        rec["params"] = (smooth, len(self.views), samples, per)
        if poly is not None:  # (V, 3) one polygon, or (4T, 4) a triangle list (triangle_list_vertices)
            poly = np.asarray(poly, np.float64)
            is_list = poly.shape[1] == 4
            if not is_list:
                poly = np.concatenate([poly, np.ones((len(poly), 1))], axis=1)
            rec["polygon"] = (sum(len(p) for p in self.polys), len(poly), 1.0 if two_sided else 0.0,
                              1.0 if is_list else 0.0)
            self.polys.append(poly)
        self.views.extend(light_views)
        self.view_lights.extend([len(self.records)] * len(light_views))
        self.records.append(rec)

    def finish(self) -> LightBuffers:
        lights = np.array(self.records, LIGHT_DTYPE) if self.records else np.zeros(0, LIGHT_DTYPE)
        vertices = (np.concatenate(self.polys) if self.polys else np.zeros((0, 4))).astype(np.float32)
        return LightBuffers(lights, self.views, vertices, self.warnings, self.view_lights, self.skipped)


@dataclass
class StaticLights:
    """The lights that only the geometry, the materials and the settings place: the emissive meshes' clusters (the
    arguments of their records) and the sky's shadow views. A pipeline keeps them across light and world edits."""
    emitters: list  # (args, kwargs) of _Records.add
    sky_views: list  # ShadowView per sky direction


def static_key(scene: Scene, trapping: list) -> str:
    """What static_lights reads of `scene` beside the settings: the emissive triangles and their radiance, the
    trapping shells' triangles and the scene's bounding sphere (the sky's views span it, the emitters' cubes reach
    across it). Moving an object that emits nothing within the bounds keeps it."""
    idx, radiance = em.emissive_triangles(scene)
    return hash_parts(scene.positions[idx], radiance, [scene.positions[s] for s in trapping], *_scene_radius(scene))


def static_lights(scene: Scene, settings: ShadowSettings | None = None, trapping: list | None = None) -> StaticLights:
    """The emitters' records and the sky's views of `scene` (build_light_buffers takes them)."""
    s = settings or ShadowSettings()
    return StaticLights(_emitter_lights(scene, s, trapping), _sky_views(scene, s))


def build_light_buffers(scene: Scene, settings: ShadowSettings | None = None, trapping: list | None = None,
                        static: StaticLights | None = None) -> LightBuffers:
    """Pack every light (and emissive triangle) into GPU records and list the shadow views they sample.
    `trapping`: the closed emitters whose inner light is trapped (default emitters.trapping_shells(scene)).
    `static`: static_lights of this scene's geometry, materials, settings and trapping (made here if None)."""
    s = settings or ShadowSettings()
    static = static or static_lights(scene, s, trapping)
    out = _Records()
    for light in scene.lights:
        reason = unreachable(scene, light)
        if reason:
            out.skipped.append(f"light '{light.name}': {reason}")
            continue
        _add_lamp(out, scene, light, s)
    for args, kwargs in static.emitters:
        out.add(*args, **kwargs)
    radiance = np.asarray(scene.world.color, np.float64)[:3]
    if max(radiance) > 0 and len(scene.positions):
        out.add(LIGHT_SKY, radiance, light_views=static.sky_views, samples=len(static.sky_views), per=1)
    return out.finish()


def _sky_views(scene: Scene, s: ShadowSettings) -> list:
    """The world is one light of radiance L (its colour × strength) from every direction, shadowed from
    `sky_directions` directions d_k, each an orthographic map looking along −d_k whose ShadowView.emitter holds
    (d_k, its solid angle 4π/K): direct/eval.glsl weighs their visibility by cosine (diffuse) or by the glossy
    lobe, lpv/inject.glsl lights each map's texels with L·(4π/K). These views, whatever the world's colour."""
    if not len(scene.positions):
        return []
    dirs = cam.sphere_directions(s.sky_directions) if s.sky_directions > 0 else np.zeros((0, 3))
    share = 4 * math.pi / max(len(dirs), 1)
    v = []
    for d in dirs:
        view = ortho_view(scene, -d, s.sky_resolution)
        # Hard shadows: the directions' average is the penumbra (filtering each map would only blur where the
        # next direction's edge lies).
        view.emit_normal, view.emit_share, view.pcf_radius = d, share, 0
        v.append(view)
    return v


def unreachable(scene: Scene, light: Light) -> str:
    """Why a light cannot light the scene, or "": no power or no colour, or a one-sided area light whose whole
    side faces away from every point of the scene's bounds (exact: its light leaves through its back)."""
    if not light.power > 0 or max(_color(light)) <= 0:
        return "zero power"
    if light.type == "AREA" and len(scene.positions):  # Blender's area lights emit from their front only
        lo, hi = scene.bounds()
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        origin = np.asarray(light.matrix_world, np.float64)[:3, 3]
        if ((corners - origin) @ np.asarray(light.direction, np.float64)).max() <= 0:
            return "faces away from the whole scene"
    return ""


def _add_lamp(out: _Records, scene: Scene, light: Light, s: ShadowSettings) -> None:
    """One Blender light: its record and its shadow views (sun: one orthographic map, point: a cube, spot: one
    perspective map, area: a cube per shadow sample point)."""
    color = _color(light)
    if light.type == "SUN":
        v = [ortho_view(scene, light.direction, s.sun_resolution)] if light.cast_shadow else []
        out.add(LIGHT_SUN, color * light.power, direction=light.direction, light_views=v, samples=len(v), per=1)
    elif light.type in ("POINT", "SPOT"):
        intensity = color * light.power / (4 * math.pi)
        near, far = _near_far(scene, light.position)
        if light.type == "POINT":
            v = cube_views(light.position, s.cube_resolution, near, far) if light.cast_shadow else []
            out.add(LIGHT_POINT, intensity, light.position, _falloff_radius2(light), light_views=v,
                    samples=1 if v else 0, per=6)
        else:
            cos_half = math.cos(light.spot_size / 2)
            smooth = 1.0 / ((1.0 - cos_half) * light.spot_blend) if light.spot_blend > 0 and cos_half < 1 else 0.0
            v = [spot_view(scene, light, s.spot_resolution, near, far)] if light.cast_shadow else []
            out.add(LIGHT_SPOT, intensity, light.position, _falloff_radius2(light), light.direction, cos_half,
                    smooth, light_views=v, samples=1 if v else 0, per=1)
    elif light.type == "AREA":
        poly, area = area_polygon(light)
        if area <= 0:
            out.warnings.append(f"area light '{light.name}' has zero size and is ignored")
            return
        radiance = color * light.power / (math.pi * area)
        v = []
        pts = area_sample_points(light, s.area_samples) if light.cast_shadow else []
        for point in pts:
            v.extend(cube_views(point, s.area_cube_resolution, *_near_far(scene, point),
                                np.asarray(light.direction, np.float64), area / len(pts), one_sided=True))
        out.add(LIGHT_POLYGON, radiance, poly.mean(axis=0), 0.0, light.direction, light_views=v,
                samples=len(pts), per=6, poly=poly)
    else:
        out.warnings.append(f"light '{light.name}' of type {light.type} is not supported and is ignored")


def triangle_list_vertices(vertices: np.ndarray, radiance: np.ndarray, color: np.ndarray,
                           one_sided: np.ndarray | None = None) -> np.ndarray:
    """(4T, 4) polygon-buffer rows of a triangle list: per triangle its three vertices (w = 1), then its radiance
    relative to the light record's colour (rgb; w = 1 where it emits along its winding normal only, else 0).
    shaders/common/light_eval.glsl reads them."""
    t = len(vertices)
    out = np.zeros((t, 4, 4))
    out[:, :3, :3] = vertices
    out[:, :3, 3] = 1.0
    out[:, 3, :3] = np.divide(radiance, color, out=np.zeros_like(radiance), where=color > 0)
    out[:, 3, 3] = 0.0 if one_sided is None else one_sided
    return out.reshape(-1, 4)


def _emitter_lights(scene: Scene, s: ShadowSettings, trapping: list | None) -> list:
    """Every emissive triangle, in ≤ emissive_sample_budget/2 two-sided polygon lights (common/emitters.py), each
    shadowed from its sample points on both sides of the surface (not the trapped inner side of a closed one): the
    (args, kwargs) of their records (_Records.add)."""
    half = max(1, s.emissive_sample_budget // 2)
    clusters = [(c, [x for x in em.side_samples(c) if not x[3]])
                for c in em.cluster_emitters(scene, half, half, trapping)]
    resolution = emitter_cube_resolution(sum(len(samples) for _, samples in clusters), s)
    out = []
    for c, samples in clusters:
        color = c.radiance.max(axis=0)
        v = []
        for point, normal, share, _ in samples:
            v.extend(cube_views(point, resolution, *_near_far(scene, point), normal, share / c.area))
        out.append(((LIGHT_POLYGON, color, c.centroid, 0.0, c.normal), dict(
            light_views=v, samples=len(samples), per=6, two_sided=True,
            poly=triangle_list_vertices(c.vertices, c.radiance, color, c.one_sided))))
    return out


def emitter_cube_resolution(cubes: int, s: ShadowSettings) -> int:
    """Texels per side of each emitter cube's faces: sample_cube_resolution, or less (a multiple of 16) where the
    scene's `cubes` would outgrow emissive_texels together: on the emitters measured, more sample points at coarser
    faces shadowed better than fewer at finer ones (benchmarks/results/llvmpipe/emitters.md), and an atlas past its
    size would halve every light's maps (common/atlas.py)."""
    fit = int(math.sqrt(s.emissive_texels / (6 * max(cubes, 1)))) // 16 * 16
    return max(16, min(s.sample_cube_resolution, fit))
