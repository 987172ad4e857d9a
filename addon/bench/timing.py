# SPDX-License-Identifier: GPL-3.0-or-later
"""Frame times as the benchmark measures them: a warm-up render (shader compilation, uploads), then the median of
N full frames, each with every pass cache cleared, plus the scene extraction time; and the machine they ran on."""
from __future__ import annotations

import os
import platform
import statistics
import time


def time_extraction(resolution, repeats: int) -> float:
    """Median seconds to extract the open bpy scene (what every update in Blender pays before rendering)."""
    import bpy

    from ..extract import extract_scene

    runs = []
    for _ in range(max(1, repeats)):
        start = time.perf_counter()
        extract_scene(bpy.context.evaluated_depsgraph_get(), resolution)
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


def time_ours(engine, scene, settings, repeats: int):
    """Warm-up, then `repeats` full renders with the pass cache cleared; (median seconds, median per pass, last)."""
    engine.render(scene, settings)  # compiles shaders, uploads
    runs = []
    for _ in range(repeats):
        engine.clear_cache()
        start = time.perf_counter()
        result = engine.render(scene, settings)
        runs.append((time.perf_counter() - start, result))
    seconds = statistics.median(r[0] for r in runs)
    names = [k for k in runs[-1][1].timings if k != "total"]
    passes = {k: statistics.median(r[1].timings.get(k, 0.0) for r in runs) for k in names}
    return seconds, passes, runs[-1][1]


def machine_info(engine) -> dict:
    info = {"cpu_count": os.cpu_count(), "platform": platform.platform()}
    try:
        gl = engine.gl_info()
        info["gl_renderer"] = gl["renderer"]
        info["gl_version"] = gl["version"]
    except Exception as exc:  # noqa: BLE001 — the report says so rather than failing
        info["gl_renderer"] = f"unknown ({exc})"
    return info
