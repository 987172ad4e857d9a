# SPDX-License-Identifier: GPL-3.0-or-later
"""Cycles' vertex bake, the reference for `bounce_gi.bake_color_attribute`: type DIFFUSE, pass filter INDIRECT
(optionally DIRECT too), colour off, into a FLOAT_COLOR point attribute (irradiance / π per vertex, the corners of a
vertex averaged), with the reference settings of addon/reference/cycles.py and two seeds. Runs inside bpy; the
render settings, selection and active object are restored and the temporary attribute removed afterwards.

Developer tooling (tests/blender/test_bake.py, benchmarks/bake_bench.py): not part of the extension zip."""
import time

import bpy
import numpy as np

TEMP = "CyclesBakeReference"


def cycles_vertex_bake(objects, samples: int, seeds=(1, 2), bounces: int = 8, direct: bool = False):
    """({object name: (V, 3) mean of the seeds}, [per-seed dicts], Cycles' bake seconds summed over the seeds)."""
    from . import settings_snapshot
    from .cycles import ReferenceSettings, configure_cycles

    scene, layer = bpy.context.scene, bpy.context.view_layer
    snap = settings_snapshot.snapshot(scene, layer)
    selected, active = [o for o in layer.objects if o.select_get()], layer.objects.active
    per_seed, seconds = [], 0.0
    try:
        for seed in seeds:
            configure_cycles(scene, layer, ReferenceSettings(8, 8, samples=samples, bounces=bounces), seed, "//unused")
            bpy.ops.object.select_all(action="DESELECT")
            for o in objects:
                attr = o.data.color_attributes.get(TEMP) or o.data.color_attributes.new(TEMP, "FLOAT_COLOR", "POINT")
                o.data.color_attributes.active_color = attr
                o.select_set(True)
            layer.objects.active = objects[0]
            start = time.perf_counter()
            bpy.ops.object.bake(type="DIFFUSE", pass_filter={"INDIRECT", "DIRECT"} if direct else {"INDIRECT"},
                                target="VERTEX_COLORS")
            seconds += time.perf_counter() - start
            values = {}
            for o in objects:
                attr = o.data.color_attributes[TEMP]
                v = np.empty(len(attr.data) * 4, np.float32)
                attr.data.foreach_get("color", v)
                values[o.name] = v.reshape(-1, 4)[:, :3].copy()
            per_seed.append(values)
    finally:
        for o in objects:
            attr = o.data.color_attributes.get(TEMP)
            if attr is not None:
                o.data.color_attributes.remove(attr)
        bpy.ops.object.select_all(action="DESELECT")
        for o in selected:
            o.select_set(True)
        layer.objects.active = active
        settings_snapshot.restore(snap)
    mean = {name: np.mean([s[name] for s in per_seed], axis=0) for name in per_seed[0]}
    return mean, per_seed, seconds


def rel_l1(ours: dict, ref: dict) -> float:
    """Σ|x − r| / Σ|r| over every vertex and channel of every mesh."""
    names = sorted(ref)
    x = np.concatenate([ours[n] for n in names])
    r = np.concatenate([ref[n] for n in names])
    return float(np.abs(x - r).sum() / np.abs(r).sum())
