# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi bench --incremental`: what one update costs in a long-lived engine, by kind of edit.

An update is what the add-on does after an edit: extract the evaluated scene, then `Engine.render`, whose pass cache
re-runs only the passes whose inputs changed (gpu_kernels/gl/pass_cache.py). Each kind of edit is applied to the open
.blend with bpy (+d, +2d, … from the scene as it was, then restored exactly), and the median of `repeats`
updates is reported with every run.
Beside them: Cycles re-rendering the same scene at 1 sample + OpenImageDenoise (the peer an edit must beat), and
what the LPV's cached transport holds in memory at a few grid resolutions. The file is never saved.
"""
from __future__ import annotations

import os
import statistics
import time

from ..scene_io import load_scene

KINDS = ("full", "unchanged", "camera_only", "light_move", "light_power", "material_change", "world_change",
         "object_move")
STEP = 0.05  # metres (or colour units) per edit: small enough to stay a "typical" interactive nudge
# An object's move per edit as a share of the scene's size, where that is less than STEP: in a scene 10 cm across
# (product_shot) 5 cm steps lifted a coin out of the scene, which changes the grids (a new frame, not a nudge).
NUDGE = 0.025
# The targets (fractions of `full`) an edit is held to, and the speed-up over Cycles 1 spp + OIDN of a light move.
TARGETS = {"unchanged": 0.01, "camera_only": 0.25, "light_move": 0.10, "light_power": 0.10, "material_change": 0.10,
           "world_change": 0.10, "object_move": 0.40}
PEER_SPEEDUP = 3.0
MEMORY_RESOLUTIONS = (32, 64, 128)


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
    """The Principled / Diffuse BSDF Base Color input of a material's nodes, where it is a value (not linked)."""
    if material.use_nodes and material.node_tree:
        for node in material.node_tree.nodes:
            for name in ("Base Color", "Color"):
                sock = node.inputs.get(name) if node.type in ("BSDF_PRINCIPLED", "BSDF_DIFFUSE") else None
                if sock is not None and not sock.is_linked:
                    return sock
    return None


def _colour_values(material):
    """The colour a material edit nudges: its Principled / Diffuse Base Color value, its viewport colour if it uses
    no nodes (what extraction reads then), or None (its colour is an image or a node tree's)."""
    socket = _base_color_socket(material)
    if socket is not None:
        return socket.default_value
    return None if material.use_nodes and material.node_tree else material.diffuse_color


def _extent(objects) -> float:
    """The largest side of the box around `objects`' world-space bounding boxes (m)."""
    import numpy as np

    corners = np.concatenate([np.c_[np.array(o.bound_box), np.ones(8)] @ np.array(o.matrix_world).T
                              for o in objects])[:, :3]
    return float((corners.max(axis=0) - corners.min(axis=0)).max())


def _stepper(get, put, value_at):
    """edit(k): the value saved now, `k` steps on (value_at(base, k)); edit(0) restores it exactly."""
    base = get()
    return lambda k: put(value_at(base, k))


def _channel(values, index):
    """(get, put) of one channel of a colour or vector property."""
    def put(v):
        values[index] = v
    return (lambda: values[index]), put


def _world_edit(scene):
    """An edit of the world: its Background node's blue (or the world's viewport colour's) nudged; a world of
    strength 0 is switched on (strength 1) while edited."""
    world = scene.world
    if world is None:
        return "the scene has no world"
    node = next((n for n in world.node_tree.nodes if n.type == "BACKGROUND"), None) if world.node_tree else None
    sock = node.inputs.get("Color") if node is not None else None
    if sock is not None and sock.is_linked:
        return "the world's colour is driven by a node tree (a sky texture), not a value to nudge"
    strength = node.inputs.get("Strength") if node is not None else None
    colour = _stepper(*_channel(sock.default_value if sock is not None else world.color, 2),
                      lambda base, k: base + k * STEP)
    power = None if strength is None else strength.default_value

    def edit(k):
        if strength is not None:
            strength.default_value = power if k == 0 or power > 0 else 1.0
        colour(k)
    return edit


def _edits(bpy):
    """kind → a function edit(k) applying the k-th small change from the scene as it is now (edit(0) restores it),
    or a reason the scene has nothing to edit."""
    scene = bpy.context.scene
    meshes = [o for o in scene.objects if o.type == "MESH" and o.visible_get()]
    lights = [o for o in scene.objects if o.type == "LIGHT" and o.visible_get()]
    edits = {}

    def mover(obj, axis, step=STEP):
        return _stepper(*_channel(obj.location, axis), lambda base, k: base + k * step)

    edits["camera_only"] = mover(scene.camera, 0) if scene.camera else "the scene has no camera"
    edits["light_move"] = mover(lights[0], 0) if lights else "the scene has no light object (emission only)"
    if lights:
        data = lights[0].data
        edits["light_power"] = _stepper(lambda: data.energy, lambda v: setattr(data, "energy", v),
                                        lambda base, k: base * 1.25 ** k)
    else:
        edits["light_power"] = "the scene has no light object (emission only)"
    edits["world_change"] = _world_edit(scene)
    if meshes:
        # the smallest object: moving a wall of a room would be an unusual edit
        smallest = min(meshes, key=lambda o: max(o.dimensions))
        edits["object_move"] = mover(smallest, 2, min(STEP, NUDGE * _extent(meshes)))
    else:
        edits["object_move"] = "the scene has no mesh object"
    # the first material whose base colour is a value (an image's colour is no nudge: editing it changed nothing)
    materials = [s.material for o in meshes for s in o.material_slots if s.material]
    values = next((v for v in map(_colour_values, materials) if v is not None), None)
    if values is not None:
        # darker each step where a few brighter steps would leave [0, 1]
        edits["material_change"] = _stepper(*_channel(values, 0), lambda base, k: base + (
            k * STEP if base + 4 * STEP <= 1.0 else -k * STEP))
    else:
        edits["material_change"] = "no mesh's material has a base colour value (an unlinked Base Color)"
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
        detail[kind] = {"extract": statistics.median(r[1] for r in runs), "runs": [r[0] for r in runs],
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
        for k in range(1, repeats + 1):  # always onward: the cache keeps a pass's last outputs, so going back
            edit(k)                      # and forth would find the previous state cached, not measure an edit
            bpy.context.view_layer.update()
            runs.append(_update(engine, settings, scene_resolution))
        record(kind, runs)
        edit(0)  # the scene exactly as it was, and the engine's cache in step with it,
        bpy.context.view_layer.update()  # so the next kind measures its own edit only
        _update(engine, settings, scene_resolution)
    return {**{k: out.get(k) for k in KINDS}, "detail": detail}


def time_cycles_1spp_oidn(resolution, tmp: str, repeats: int = 3) -> float | None:
    """Median seconds of Cycles re-rendering the open scene at 1 sample + OpenImageDenoise (after a warm-up), as
    bench's peers are timed (peers.render_exr); None if Cycles fails here."""
    import bpy

    from ..reference.cycles import ReferenceSettings, configure_cycles, saved_attributes, settings_to_save
    from .peers import render_exr

    scene, view_layer = bpy.context.scene, bpy.context.view_layer
    path = os.path.join(tmp, "cycles_1spp_oidn.exr")
    with saved_attributes(settings_to_save(scene, view_layer) + [(scene.cycles, "denoiser")]):
        configure_cycles(scene, view_layer, ReferenceSettings(*resolution, samples=1), 3, path)
        scene.cycles.use_denoising = True
        scene.cycles.denoiser = "OPENIMAGEDENOISE"
        try:
            runs = [render_exr(bpy, path)[0] for _ in range(repeats + 1)][1:]
        except Exception:  # noqa: BLE001 — a peer failing must not end the benchmark
            return None
    return statistics.median(runs)


def transfer_memory(scene) -> list:
    """The LPV cached transport's size at MEMORY_RESOLUTIONS (estimated from the surface area)."""
    from ...gpu_kernels.lpv.passes import transfer_estimate
    from ...gpu_kernels.lpv.settings import LpvSettings

    return [transfer_estimate(scene, LpvSettings(resolution=n)) for n in MEMORY_RESOLUTIONS]


def vct_memory(scene) -> list:
    """What the VCT keeps across edits (vct/memory.py) at MEMORY_RESOLUTIONS, its defaults otherwise, the trace at the
    scene's resolution."""
    from dataclasses import replace

    from ...gpu_kernels.vct.memory import cached_bytes
    from ...gpu_kernels.vct.settings import VctSettings, traced_texels
    from ...gpu_kernels.voxel.voxelize import scene_area

    s, area = VctSettings(), scene_area(scene)
    traced = traced_texels(*scene.resolution, s)
    return [{"resolution": n, "bytes": cached_bytes(scene, replace(s, resolution=n), traced, area)}
            for n in MEMORY_RESOLUTIONS]


def run_incremental(path: str, res, methods, progress, repeats: int = 3) -> dict:
    import tempfile

    scene = load_scene(path, tuple(res) if res else None)
    result = {"scene": path, "resolution": list(scene.resolution), "methods": {}}
    for method in methods:
        progress(f"bench --incremental: {method}")
        result["methods"][method] = measure_incremental(tuple(scene.resolution), method, repeats)
    progress("bench --incremental: Cycles 1 spp + OIDN")
    with tempfile.TemporaryDirectory() as tmp:
        result["peers"] = {"cycles_1spp_oidn": time_cycles_1spp_oidn(tuple(scene.resolution), tmp, repeats)}
    result["lpv_transfer_memory"] = transfer_memory(scene)
    if "vct" in methods:
        result["vct_memory"] = vct_memory(scene)
    return result


def verdicts(entry: dict) -> list:
    """One line per method and kind: its fraction of `full` against TARGETS, and a light move against the peer."""
    lines, peer = [], entry.get("peers", {}).get("cycles_1spp_oidn")
    for method, m in entry["methods"].items():
        if method == "none" or not m.get("full"):
            continue
        for kind, target in TARGETS.items():
            if m.get(kind) is not None:
                share = m[kind] / m["full"]
                lines.append(f"- {method} {kind}: {share:.1%} of full (target ≤ {target:.0%}): "
                             f"{'met' if share <= target else 'NOT met'}")
        if peer and m.get("light_move"):
            speedup = peer / m["light_move"]
            lines.append(f"- {method} light_move vs Cycles 1 spp + OIDN ({peer * 1000:.0f} ms): {speedup:.2f}× "
                         f"(target ≥ {PEER_SPEEDUP:.0f}×): {'met' if speedup >= PEER_SPEEDUP else 'NOT met'}")
    return lines


def format_incremental(entry: dict) -> str:
    w, h = entry["resolution"]
    lines = [f"## incremental updates: {entry['scene']} ({w}x{h}), ms (median)", "",
             "| method | " + " | ".join(KINDS) + " |", "|---|" + "---:|" * len(KINDS)]
    for method, m in entry["methods"].items():
        cells = ["—" if m[k] is None else f"{m[k] * 1000:.1f}" for k in KINDS]
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    peer = entry.get("peers", {}).get("cycles_1spp_oidn")
    lines += ["", f"Cycles 1 spp + OIDN, same scene and resolution: "
                  f"{'failed' if peer is None else f'{peer * 1000:.1f} ms'} (median of 3 after a warm-up).", ""]
    lines += verdicts(entry) + [""]
    for method, m in entry["methods"].items():
        for k in KINDS:
            d = m["detail"].get(k, {})
            if "note" in d:
                lines.append(f"- {method} {k}: {d['note']}")
            elif d:
                runs = ", ".join(f"{r * 1000:.0f}" for r in d.get("runs", []))
                lines.append(f"- {method} {k}: runs {runs} ms; extract {d['extract'] * 1000:.1f} ms; "
                             f"re-ran {', '.join(d['rerun'])}")
    memory = entry.get("lpv_transfer_memory")
    if memory:
        lines += ["", "LPV cached transport (host memory, float32; estimated from the surface area):", "",
                  "| grid | surface voxels | clusters | T (MiB) | transport |", "|---:|---:|---:|---:|---|"]
        lines += [f"| {m['resolution']}³ | {m['surface_voxels']} | {m['clusters']} | {m['mb']:.0f} | {m['transport']} |"
                  for m in memory]
    return "\n".join(lines + vct_memory_table(entry.get("vct_memory"))) + "\n"


def vct_memory_table(memory: list | None) -> list:
    """Markdown lines: what the VCT keeps across edits, MiB per grid size (none without a measure)."""
    if not memory:
        return []
    mib = 2.0 ** 20
    lines = ["", "VCT kept across edits (GPU memory, MiB; the pools at their first size, vct/memory.py):", "",
             "| structure | " + " | ".join(f"{m['resolution']}³" for m in memory) + " |",
             "|---|" + "---:|" * len(memory)]
    for name in memory[0]["bytes"]:
        lines.append(f"| {name} | " + " | ".join(f"{m['bytes'][name] / mib:.1f}" for m in memory) + " |")
    return lines + ["| total | " + " | ".join(f"{sum(m['bytes'].values()) / mib:.1f}" for m in memory) + " |"]
