# SPDX-License-Identifier: GPL-3.0-or-later
"""The stress suite's scenes, settings and checks (tests/stress/).

`box_room` is a closed Cornell-like room with a block in it, every length scaled by `scale`; its walls and the
block's faces lie off the grids' cell boundaries at every resolution the suite uses, so a case measures the
renderer, not which voxel a wall exactly on a boundary fell into. `check_sane` is what every case asserts: all
passes finite, the light passes non-negative, Diffuse Indirect within `indirect_bound`, an analytic upper bound.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings, repair_scene
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.synthetic import box_quads, quad_scene

SIZE = (32, 24)
METHODS = ("lpv", "vct")
LIGHT_PASSES = ("Combined", "Diffuse Direct", "Diffuse Indirect", "Glossy Direct", "Glossy Indirect", "Emission", "AO")
BLOCK = ((-0.37, -0.29, 0.0), (0.23, 0.31, 1.13))  # the block inside the room (m, before scaling)
LIGHT_AT = (0.07, -0.11, 1.67)
BOUND_SLACK = 0.1


def full_only(*values):
    """Parameters that run only with --stress-full (tests/stress/conftest.py deselects them otherwise)."""
    return [pytest.param(v, marks=pytest.mark.stress_full) for v in values]


def settings(method: str, size=SIZE, **kw) -> RenderSettings:
    """Small, fast settings of `method` ("none", "lpv", "vct"); `kw` overrides that method's settings."""
    if method == "lpv":
        return RenderSettings("lpv", *size, lpv=LpvSettings(**{"resolution": 8, "rsm_resolution": 32, **kw}))
    if method == "vct":
        base = {"resolution": 16, "diffuse_cones": 5, "subrays": 1, "bounce_cones": 5}
        return RenderSettings("vct", *size, vct=VctSettings(**{**base, **kw}))
    return RenderSettings(method, *size)


def bounces_of(s: RenderSettings) -> int:
    return {"lpv": s.lpv.bounces, "vct": s.vct.bounces}.get(s.method, 0)


def light(kind: str, power: float, position, scale: float = 1.0, name: str = "lamp", **kw) -> Light:
    """A light of Blender's `kind` at `position` (scaled), shining down; power in Blender's units before the s²
    change (sun strength is an irradiance and does not change with scale)."""
    m = np.eye(4)
    m[:3, 3] = np.asarray(position, float) * scale
    if kind == "SUN":
        m[:3, :3] = np.linalg.inv(cam.look_at((0, 0, 0), (0.3, 0.2, -1.0), (0, 1, 0)))[:3, :3]
        return Light(name, "SUN", (1, 1, 1), power, m, **kw)
    extra = {"size": 0.4 * scale, "size_y": 0.3 * scale} if kind == "AREA" else {}
    return Light(name, kind, (1, 1, 1), power * scale ** 2, m, **{**extra, **kw})


def box_room(scale: float = 1.0, power: float = 100.0, kind: str = "POINT", albedo=0.7, block_albedo=(0.5, 0.3, 0.2),
             lights=None, eye=(0.83, -0.87, 1.01), target=(-0.1, 0.2, 0.95)):
    """A closed 2 × 2 × 2 m room (floor at z = 0) with a block in it, lit by one light of `kind` (or `lights`),
    camera inside; every length × `scale`, point/spot/area power × scale²."""
    s = scale
    quads = box_quads((-s, -s, 0), (s, s, 2 * s), 0)
    quads += box_quads(np.multiply(BLOCK[0], s), np.multiply(BLOCK[1], s), 1, inward=False)
    mats = [Material("walls", (albedo,) * 3 if np.isscalar(albedo) else albedo), Material("block", block_albedo)]
    if lights is None:
        lights = [light(kind, power, LIGHT_AT, s)]
    scene = quad_scene(quads, mats, lights, np.multiply(eye, s), np.multiply(target, s))
    scene.camera = replace(scene.camera, clip_start=0.01 * s, clip_end=100.0 * s)
    return scene


def furnace(albedo: float, le: float = 1.0):
    """A closed box whose walls all emit `le` and reflect `albedo`, no lights (tests/gpu/test_vct.py's furnace)."""
    quads = box_quads((-1, -1, -1), (1, 1, 1), 0)
    return quad_scene(quads, [Material("wall", (albedo,) * 3, emission=(le,) * 3)], [], (0.0, -0.5, 0.1),
                      (0.3, 1.0, -0.2))


def turned(scene, degrees: float):
    """`scene` turned `degrees` about the world's z axis: triangles, normals, lights and camera."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    m = np.eye(4, dtype=np.float32)
    m[:2, :2] = ((c, -s), (s, c))
    r = m[:3, :3]
    lights = [replace(l, matrix_world=(m @ np.asarray(l.matrix_world, np.float32)).astype(np.float32))
              for l in scene.lights]
    return replace(scene, positions=(scene.positions @ r.T).astype(np.float32),
                   normals=(scene.normals @ r.T).astype(np.float32), lights=lights,
                   camera=replace(scene.camera, matrix_world=(m @ scene.camera.matrix_world).astype(np.float32)))


def direct_bound(scene) -> float:
    """An upper bound of irradiance / π anywhere on the scene's surfaces (before reflection): the lights' bounds
    added up, plus the brightest emission and the world (a surface sees at most radiance L all round: E/π ≤ L).
    A point or spot light of power P gives E ≤ P/(4π)/d², d its distance to the nearest surface (bounded below
    by the distance to each triangle's plane and to its bounding box, whichever is larger); a sun E ≤ strength;
    an area light (one-sided, radiance P/(π·A)) E/π ≤ P/(π·A)."""
    total = max(scene.world.color)
    used = set(np.unique(scene.material_index).tolist()) if scene.triangle_count else set()
    total += max([max(scene.materials[i].emission) for i in used] or [0.0])
    for l in scene.lights:
        tint = max(l.color)
        if l.type == "SUN":
            total += tint * l.power / math.pi
        elif l.type == "AREA":
            area = l.size * (l.size_y if l.shape in ("RECTANGLE", "ELLIPSE") else l.size)
            area *= math.pi / 4 if l.shape in ("DISK", "ELLIPSE") else 1.0
            total += tint * l.power / (math.pi * area) if area > 0 else math.inf
        else:
            d = nearest_surface(scene, l.position)
            total += tint * l.power / (4 * math.pi) / d ** 2 / math.pi if d > 0 else math.inf
    return total


def nearest_surface(scene, point) -> float:
    """A lower bound of the distance from `point` to the nearest triangle."""
    if not scene.triangle_count:
        return math.inf
    p = scene.positions.astype(np.float64)
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(n, axis=1)
    plane = np.where(length > 0, np.abs(((point - p[:, 0]) * n).sum(1)) / np.maximum(length, 1e-300), 0.0)
    lo, hi = p.min(axis=1), p.max(axis=1)
    box = np.linalg.norm(np.maximum(np.maximum(lo - point, point - hi), 0.0), axis=1)
    return float(np.maximum(plane, box).min())


def indirect_bound(scene, bounces: int) -> float:
    """Diffuse Indirect ≤ D·(ρ + ρ² + … + ρ^N): the light reflected once or more leaves a surface with radiance
    at most ρ·(D + that radiance's own maximum), D = direct_bound, ρ the largest albedo, N bounces."""
    used = set(np.unique(scene.material_index).tolist()) if scene.triangle_count else set()
    rho = max([max(scene.materials[i].base_color) for i in used] or [0.0])
    series = sum(rho ** i for i in range(1, bounces + 1))
    return direct_bound(scene) * series if series > 0 else 0.0  # no bounce (or black): none, even by an inf bound


def check_sane(result, scene, s: RenderSettings) -> None:
    """What every stress case asserts of a render."""
    for name, image in result.passes.items():
        assert np.isfinite(image).all(), f"{name} has {int((~np.isfinite(image)).sum())} non-finite values"
    for name in LIGHT_PASSES:
        if name in result.passes:
            assert result.passes[name].min() >= 0.0, f"{name} is negative: {result.passes[name].min()}"
    hit = result.passes["Depth"][..., 0] < 1e9
    indirect = result.passes["Diffuse Indirect"][..., :3][hit]
    bound = indirect_bound(repair_scene(scene), bounces_of(s))  # of what was rendered: broken triangles left out
    # In the furnace the bound is attained everywhere, and a voxel method's pixels scatter about the exact value:
    # measured up to 4.8% over it (LPV 8³, one bounce); 10% slack. Elsewhere the bound is loose by 10× or more.
    assert indirect.size == 0 or indirect.max() <= bound * (1 + BOUND_SLACK), (float(indirect.max()), bound)


def rel_l1(x, ref) -> float:
    denom = float(np.abs(ref).sum())
    return float(np.abs(x - ref).sum()) / denom if denom > 0 else float(np.abs(x).sum())
