# SPDX-License-Identifier: GPL-3.0-or-later
"""`cornell_animated`: the Cornell box over four frames, one kind of change per frame, so a frame-range render
shows what each kind of change lets the engine reuse.

    frame 1  the Cornell box as `cornell`
    frame 2  the area light moves            (geometry, materials, camera unchanged)
    frame 3  the camera moves                (geometry, materials, lights unchanged)
    frame 4  the short box moves and the green wall turns blue (geometry and materials change)

Every key is CONSTANT (a step, no interpolation), so each frame differs from the one before by exactly the change
listed, and a frame equals its predecessor in every other input, bit for bit.
"""

import bpy

from .cornell_box import cornell

ANIMATED_FRAMES = (1, 4)
LIGHT_MOVE = (0.35, 0.2, 0.0)  # added to the light's location from frame 2 on
CAMERA_MOVE = (0.3, 0.0, 0.15)  # added to the camera's location from frame 3 on
BOX_MOVE = (0.0, 0.25, 0.0)  # added to the short box's location at frame 4
BLUE = (0.1, 0.15, 0.6)  # the green wall's albedo at frame 4


def _key_step(target, path, frame, before, after):
    """Key `target.path` = before at frame - 1 and after at `frame` (CONSTANT: a step at `frame`)."""
    setattr(target, path, before)
    target.keyframe_insert(path, frame=frame - 1)
    setattr(target, path, after)
    target.keyframe_insert(path, frame=frame)


def _moved(location, delta):
    return tuple(a + b for a, b in zip(location, delta))


def cornell_animated():
    """The Cornell box with a light move (frame 2), a camera move (frame 3), an object move and a material change
    (frame 4); the scene's frame range is 1-4."""
    cornell()
    prefs = bpy.context.preferences.edit
    interpolation = prefs.keyframe_new_interpolation_type
    prefs.keyframe_new_interpolation_type = "CONSTANT"  # steps, whatever the Blender version's action API
    try:
        objects = bpy.data.objects
        light, cam, box = objects["AreaLight"], objects["Camera"], objects["ShortBox"]
        _key_step(light, "location", 2, tuple(light.location), _moved(light.location, LIGHT_MOVE))
        _key_step(cam, "location", 3, tuple(cam.location), _moved(cam.location, CAMERA_MOVE))
        _key_step(box, "location", 4, tuple(box.location), _moved(box.location, BOX_MOVE))
        colour = bpy.data.materials["Green"].node_tree.nodes["Diffuse BSDF"].inputs["Color"]
        _key_step(colour, "default_value", 4, tuple(colour.default_value), (*BLUE, 1.0))
    finally:
        prefs.keyframe_new_interpolation_type = interpolation
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = ANIMATED_FRAMES
