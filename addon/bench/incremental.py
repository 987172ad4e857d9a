# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi bench --incremental`: what one update costs in a long-lived engine, by kind of edit.

An update is what the add-on does after an edit: extract the evaluated scene, then `Engine.render`, whose pass cache
re-runs only the passes whose inputs changed (gpu_kernels/gl/pass_cache.py). Each kind of edit is applied to the open
.blend with bpy (alternately +d and −d, so the scene stays put), and the median of `repeats` updates is reported.
The file is never saved.
"""
from __future__ import annotations

import statistics
import time

from ..scene_io import load_scene

KINDS = ("full", "unchanged", "camera_only", "light_move", "material_change", "object_move")
STEP = 0.05  # metres (or colour units) per edit: small enough to stay a "typical" interactive nudge


def _update(engine, settings, resolution):
    import bpy

    from ..extract import extract_scene

    start = time.perf_counter()
    scene = extract_scene(bpy.context.evaluated_depsgraph_get(), resolution)
    extracted = time.perf_counter()
    result = engine.render(scene, settings)
    end = time.perf_counter()
    return end - start, extracted - start, result


def _base_color_socket(material):
    """The input an edit of 'material colour' changes: Principled / Diffuse Base Color, else the viewport colour."""
    if material.use_nodes and material.node_tree:
        for node in material.node_tree.nodes:
            for name in ("Base Color", "Color"):
                sock = node.inputs.get(name) if node.type in ("BSDF_PRINCIPLED", "BSDF_DIFFUSE") else None
                if sock is not None and not sock.is_linked:
                    return sock
    return None


def _edits(bpy):
    """kind → a function edit(sign) applying a small change, or a reason the scene has nothing to edit."""
    scene = bpy.context.scene
    meshes = [o for o in scene.objects if o.type == "MESH" and o.visible_get()]
    lights = [o for o in scene.objects if o.type == "LIGHT" and o.visible_get()]
    edits = {}

    def mover(obj, axis):
        def edit(sign):
            obj.location[axis] += sign * STEP
        return edit

    edits["camera_only"] = mover(scene.camera, 0) if scene.camera else "the scene has no camera"
    edits["light_move"] = mover(lights[0], 0) if lights else "the scene has no light object (emission only)"
    if meshes:
        # the smallest object: moving a wall of a room would be an unusual edit
        smallest = min(meshes, key=lambda o: max(o.dimensions))
        edits["object_move"] = mover(smallest, 2)
    else:
        edits["object_move"] = "the scene has no mesh object"
    material = next((s.material for o in meshes for s in o.material_slots if s.material), None)
    socket = _base_color_socket(material) if material else None
    if socket is not None:
        def recolour(sign):
            socket.default_value[0] = min(1.0, max(0.0, socket.default_value[0] + sign * STEP))
        edits["material_change"] = recolour
    elif material is not None:
        def recolour_viewport(sign):
            material.diffuse_color[0] = min(1.0, max(0.0, material.diffuse_color[0] + sign * STEP))
        edits["material_change"] = recolour_viewport
    else:
        edits["material_change"] = "no mesh has a material"
    return edits


def measure_incremental(scene_resolution, method: str, repeats: int = 3) -> dict:
    """Seconds per update kind (median), plus extraction seconds and the passes that re-ran, for one method."""
    import bpy

    from ...gpu_kernels.engine import get_engine
    from ...gpu_kernels.settings import RenderSettings

    engine = get_engine()
    w, h = scene_resolution
    settings = RenderSettings(method=method, width=w, height=h)
    _update(engine, settings, scene_resolution)  # warm-up: shader compilation, uploads
    out, detail = {}, {}

    def record(kind, runs):
        out[kind] = statistics.median(r[0] for r in runs)
        last = runs[-1][2]
        detail[kind] = {"extract": statistics.median(r[1] for r in runs),
                        "rerun": [k for k, v in last.timings.items() if k != "total" and k not in last.skipped]}

    runs = []
    for _ in range(repeats):
        engine.clear_cache()
        runs.append(_update(engine, settings, scene_resolution))
    record("full", runs)
    record("unchanged", [_update(engine, settings, scene_resolution) for _ in range(repeats)])
    for kind, edit in _edits(bpy).items():
        if isinstance(edit, str):
            out[kind], detail[kind] = None, {"note": edit}
            continue
        runs = []
        for i in range(repeats):
            edit(1 if i % 2 == 0 else -1)
            bpy.context.view_layer.update()
            runs.append(_update(engine, settings, scene_resolution))
        record(kind, runs)
        if repeats % 2:
            edit(-1)  # leave the scene as it was (the last +d undone), and the engine's cache in step with it,
            bpy.context.view_layer.update()  # so the next kind measures its own edit only
            _update(engine, settings, scene_resolution)
    return {**{k: out.get(k) for k in KINDS}, "detail": detail}


def run_incremental(path: str, res, methods, progress, repeats: int = 3) -> dict:
    scene = load_scene(path, tuple(res) if res else None)
    result = {"scene": path, "resolution": list(scene.resolution), "methods": {}}
    for method in methods:
        progress(f"bench --incremental: {method}")
        result["methods"][method] = measure_incremental(tuple(scene.resolution), method, repeats)
    return result


def format_incremental(entry: dict) -> str:
    w, h = entry["resolution"]
    lines = [f"## incremental updates: {entry['scene']} ({w}x{h}), ms (median)", "",
             "| method | " + " | ".join(KINDS) + " |", "|---|" + "---:|" * len(KINDS)]
    for method, m in entry["methods"].items():
        cells = ["—" if m[k] is None else f"{m[k] * 1000:.1f}" for k in KINDS]
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    lines.append("")
    for method, m in entry["methods"].items():
        for k in KINDS:
            d = m["detail"].get(k, {})
            if "note" in d:
                lines.append(f"- {method} {k}: {d['note']}")
            else:
                lines.append(f"- {method} {k}: extract {d['extract'] * 1000:.1f} ms; re-ran {', '.join(d['rerun'])}")
    return "\n".join(lines) + "\n"
