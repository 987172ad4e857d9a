# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender → `gpu_kernels.scene.Scene`: the only place that reads scene data through bpy.

One module per thing extracted, each turning bpy data into the core's dataclasses:
    meshes.py     evaluated meshes of the visible instances → world-space triangle arrays
    materials.py  node materials → Material, image textures → Texture
    lights.py     light objects → Light
    camera.py     the active camera → Camera, and the render size
    world.py      the world → World (a constant radiance)
`extract_scene` walks the depsgraph's object instances once and hands each to its extractor.
"""
from __future__ import annotations

import numpy as np

from ...gpu_kernels.scene import Light, Scene
from .camera import pixel_aspect, read_camera, render_resolution
from .errors import ExtractError
from .lights import read_light
from .materials import MaterialTable
from .meshes import GEOMETRY_TYPES, Geometry
from .world import read_world

__all__ = ["ExtractError", "extract_scene"]


def extract_scene(depsgraph, resolution=None, require_camera: bool = True) -> Scene:
    """Build a Scene from an evaluated depsgraph. `resolution` overrides the scene's render size (W, H). Without
    `require_camera` (the viewport draws from its own view) a scene with no usable camera gets camera None."""
    scene = depsgraph.scene_eval
    warnings: list[str] = []
    materials = MaterialTable(warnings)
    geometry = Geometry(materials.index, warnings)
    lights: list[Light] = []
    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.original.hide_render:
            continue
        matrix = np.array(inst.matrix_world, np.float64)
        if obj.type == "LIGHT":
            light, warns = read_light(obj, matrix)
            lights.append(light)
            warnings.extend(warns)
        elif obj.type in GEOMETRY_TYPES and inst.show_self:
            geometry.add_instance(obj, matrix)
    render = scene.render
    return Scene(**geometry.arrays(), materials=materials.materials, textures=materials.textures, lights=lights,
                 world=read_world(scene, warnings), camera=camera_of(scene, require_camera),
                 resolution=render_resolution(render, resolution), pixel_aspect=pixel_aspect(render),
                 warnings=warnings)


def camera_of(scene, required: bool):
    """read_camera, or None when the camera is optional and missing or unsupported."""
    try:
        return read_camera(scene)
    except ExtractError:
        if required:
            raise
        return None
