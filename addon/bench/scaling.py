# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi bench --scaling`: frame time against triangle count, grid size and image resolution, with the
fitted log-log slope of each (time ∝ xᵇ: b ≈ 1 is linear; b ≈ 0 means that size does not drive the cost).

The scenes are synthetic (no bpy): a floor and an icosphere of 20·4ˢ triangles, lit by a sun, so the triangle
count can go from 20k to 1.3M with nothing else changing. Times are full frames (every pass cache cleared), median
of `repeats` after a warm-up.
"""
from __future__ import annotations

import math
import statistics
import time
from dataclasses import replace

import numpy as np


def synthetic_scene(subdivisions: int, resolution=(320, 240)):
    """Floor (4 m square) + icosphere (radius 1 m, 20·4^subdivisions triangles) under a tilted sun."""
    import trimesh

    from ...gpu_kernels.common import camera as cam
    from ...gpu_kernels.scene import Camera, Light, Material, Scene, World

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    sphere_pos = (sphere.vertices[sphere.faces] + (0, 0, 1.0)).astype(np.float32)
    sphere_nrm = (sphere.vertices[sphere.faces] / np.linalg.norm(sphere.vertices[sphere.faces], axis=-1,
                                                                  keepdims=True)).astype(np.float32)
    a, b, c, d = (-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)
    floor_pos = np.array([[a, b, c], [a, c, d]], np.float32)
    floor_nrm = np.broadcast_to(np.float32([0, 0, 1]), (2, 3, 3))
    pos = np.concatenate([floor_pos, sphere_pos])
    nrm = np.concatenate([floor_nrm, sphere_nrm]).astype(np.float32)
    mat = np.concatenate([np.zeros(2, np.int32), np.ones(len(sphere_pos), np.int32)])
    tilt = math.radians(35)
    sun = np.eye(4)
    sun[1:3, 1:3] = [[math.cos(tilt), -math.sin(tilt)], [math.sin(tilt), math.cos(tilt)]]
    eye = np.array([4.0, -4.0, 3.0])
    cam_to_world = np.linalg.inv(cam.look_at(eye, (0, 0, 0.7), (0, 0, 1)))
    return Scene(pos, nrm, np.zeros((len(pos), 3, 2), np.float32), mat,
                 [Material("floor", (0.8, 0.8, 0.8)), Material("sphere", (0.8, 0.3, 0.2))], [],
                 [Light("sun", "SUN", (1, 1, 1), 3.0, sun)], World((0.05, 0.05, 0.05)), Camera(cam_to_world),
                 resolution=tuple(resolution))


SLOW_FRAME_S = 5.0  # a point whose warm-up frame takes longer is timed once (scaling, not noise, dominates there)


def _frame_seconds(engine, scene, settings, repeats: int) -> float:
    start = time.perf_counter()
    engine.render(scene, settings)  # warm-up
    if time.perf_counter() - start > SLOW_FRAME_S:
        repeats = 1
    runs = []
    for _ in range(repeats):
        engine.clear_cache()
        start = time.perf_counter()
        engine.render(scene, settings)
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


def fit_slope(xs, ys) -> float | None:
    """b of the least-squares fit log y = a + b log x (None with fewer than two distinct points)."""
    xs, ys = np.asarray(xs, np.float64), np.asarray(ys, np.float64)
    ok = (xs > 0) & (ys > 0)
    if len(np.unique(xs[ok])) < 2:
        return None
    return float(np.polyfit(np.log(xs[ok]), np.log(ys[ok]), 1)[0])


def _series(name, xs, measure, progress) -> dict:
    points = []
    for x in xs:
        progress(f"bench --scaling: {name} {x}")
        points.append({"x": x, "seconds": measure(x)})
    return {"x_name": name, "points": points, "slope": fit_slope([p["x"] for p in points],
                                                                  [p["seconds"] for p in points])}


def run_scaling(quick: bool, progress, methods=("none", "lpv", "vct")) -> dict:
    from ...gpu_kernels.engine import get_engine
    from ...gpu_kernels.lpv.settings import LpvSettings
    from ...gpu_kernels.settings import RenderSettings
    from ...gpu_kernels.vct.settings import VctSettings

    engine = get_engine()
    repeats = 1 if quick else 3
    subdivisions = (3, 4, 5) if quick else (5, 6, 7, 8)  # 1.3k…20k quick; 20k, 82k, 328k, 1.3M full
    resolutions = ((80, 60), (160, 120)) if quick else ((160, 120), (320, 240), (640, 480), (1280, 960))
    lpv_grids = (8, 16) if quick else (16, 32, 64)
    vct_grids = (16, 32) if quick else (32, 64, 128)
    base = (160, 120) if quick else (320, 240)
    scenes = {s: synthetic_scene(s, base) for s in subdivisions}
    out = {"quick": quick, "resolution": list(base), "series": {}}
    for method in methods:
        settings = RenderSettings(method=method, width=base[0], height=base[1])
        out["series"][f"{method}_triangles"] = _series(
            "triangles", [scenes[s].triangle_count for s in subdivisions],
            lambda n: _frame_seconds(engine, next(sc for sc in scenes.values() if sc.triangle_count == n),
                                     settings, repeats), progress)
        mid = scenes[subdivisions[1]]
        out["series"][f"{method}_pixels"] = _series(
            "pixels", [w * h for w, h in resolutions],
            lambda px: _frame_seconds(engine, mid, replace(settings, **dict(zip(
                ("width", "height"), next(r for r in resolutions if r[0] * r[1] == px)))), repeats), progress)
        if method == "lpv":
            out["series"]["lpv_grid"] = _series("cells", [g ** 3 for g in lpv_grids], lambda c: _frame_seconds(
                engine, mid, replace(settings, lpv=replace(LpvSettings(), resolution=round(c ** (1 / 3)))),
                repeats), progress)
        if method == "vct":
            out["series"]["vct_grid"] = _series("voxels", [g ** 3 for g in vct_grids], lambda c: _frame_seconds(
                engine, mid, replace(settings, vct=replace(VctSettings(), resolution=round(c ** (1 / 3)))),
                repeats), progress)
    return out


def format_scaling(report: dict) -> str:
    lines = [f"## scaling (full frames, median; base resolution {report['resolution'][0]}x{report['resolution'][1]})",
             "", "| series | x | ms |", "|---|---:|---:|"]
    for name, s in report["series"].items():
        for p in s["points"]:
            lines.append(f"| {name} | {p['x']} | {p['seconds'] * 1000:.1f} |")
    lines += ["", "| series | log-log slope |", "|---|---:|"]
    lines += [f"| {name} | {'—' if s['slope'] is None else format(s['slope'], '.2f')} |"
              for name, s in report["series"].items()]
    return "\n".join(lines) + "\n"
