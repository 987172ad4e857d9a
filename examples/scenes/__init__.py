# SPDX-License-Identifier: GPL-3.0-or-later
"""Example scenes for Bounce GI, built in code with bpy.

Used by the demo, the tests (comparisons against Cycles) and benchmarks.
Units are metres, Z up. Every scene has exactly one camera, renders at
160x120 by default, and has a black world (strength 0) unless stated.

    from examples import scenes
    scenes.build("cornell")            # replaces the current bpy data
    scenes.save("cornell", "/tmp/cornell.blend")

Materials are Diffuse BSDF (exact albedo, docs/conventions.md, Materials) with the
viewport display colour set to the same albedo, unless a scene says
otherwise. Image textures are generated in code and packed into the .blend.

The scenes live in modules by kind, built from the pieces in helpers.py:
cornell_box.py (cornell, cornell_emissive), stage.py (the light_* scenes,
textured, principled, camera_*), extraction_scene.py (extraction) and
rooms.py (spot_room, courtyard), animated.py (cornell_animated: a
change per frame). This module holds the registry, build()
and save(), and re-exports the public names of those modules, so
`scenes.<name>` reaches all of them.
"""

import bpy  # must come before bmesh/mathutils: the bpy wheel puts them on the path

from .animated import ANIMATED_FRAMES, cornell_animated
from .cornell_box import (CORNELL_EMISSION_STRENGTH, CORNELL_GREEN, CORNELL_LIGHT_POWER,
                          CORNELL_LIGHT_SIZE, CORNELL_RED, CORNELL_WHITE, cornell, cornell_emissive)
from .extraction_scene import CUSTOM_NORMAL, extraction
from .helpers import (CHECKER_A, CHECKER_B, box, camera, checker_image, diffuse_material,
                      emission_material, light, look_at_rotation, mesh_object, principled_material, quad,
                      quad_faces, reset, set_world, textured_material, uv_sphere)
from .rooms import COURTYARD_OPENING, COURTYARD_SUN_ROTATION, courtyard, spot_room
from .stage import (AREA_LOCATION, AREA_ROTATION, CUBE_LOCATION, POINT_LOCATION, SPOT_LOCATION,
                    STAGE_CUBE, STAGE_WHITE, SUN_ROTATION, camera_ortho, camera_shift, light_area_disk,
                    light_area_square, light_mixed, light_point, light_point_soft, light_spot, light_sun,
                    principled, textured)

RESOLUTION = (160, 120)

__all__ = ["ANIMATED_FRAMES", "cornell_animated",
           "CORNELL_EMISSION_STRENGTH", "CORNELL_GREEN", "CORNELL_LIGHT_POWER", "CORNELL_LIGHT_SIZE", "CORNELL_RED",
           "CORNELL_WHITE", "cornell", "cornell_emissive", "CUSTOM_NORMAL", "extraction", "CHECKER_A", "CHECKER_B",
           "box", "camera", "checker_image", "diffuse_material", "emission_material", "light", "look_at_rotation",
           "mesh_object", "principled_material", "quad", "quad_faces", "reset", "set_world", "textured_material",
           "uv_sphere", "COURTYARD_OPENING", "COURTYARD_SUN_ROTATION", "courtyard", "spot_room", "AREA_LOCATION",
           "AREA_ROTATION", "CUBE_LOCATION", "POINT_LOCATION", "SPOT_LOCATION", "STAGE_CUBE", "STAGE_WHITE",
           "SUN_ROTATION", "camera_ortho", "camera_shift", "light_area_disk", "light_area_square", "light_mixed",
           "light_point", "light_point_soft", "light_spot", "light_sun", "principled", "textured", "RESOLUTION",
           "SCENES", "build", "save"]


# --------------------------------------------------------------------------- registry

SCENES = {
    "cornell": cornell,
    "cornell_emissive": cornell_emissive,
    "light_sun": light_sun,
    "light_point": light_point,
    "light_point_soft": light_point_soft,
    "light_spot": light_spot,
    "light_area_square": light_area_square,
    "light_area_disk": light_area_disk,
    "light_mixed": light_mixed,
    "textured": textured,
    "principled": principled,
    "camera_shift": camera_shift,
    "camera_ortho": camera_ortho,
    "extraction": extraction,
    "spot_room": spot_room,
    "courtyard": courtyard,
    "cornell_animated": cornell_animated,
}


def build(name):
    """Reset Blender and build scene `name` into the current bpy data."""
    if name not in SCENES:
        raise KeyError(f"unknown scene {name!r}; known: {', '.join(SCENES)}")
    reset()
    scene = bpy.context.scene
    scene.name = name
    set_world()
    SCENES[name]()
    scene.render.resolution_x, scene.render.resolution_y = RESOLUTION
    scene.render.resolution_percentage = 100
    scene.frame_set(1)
    bpy.context.view_layer.update()


def save(name, path):
    """Build scene `name` and save it as an uncompressed, self-contained .blend."""
    import os

    build(name)
    path = os.path.abspath(path)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    bpy.context.preferences.filepaths.save_version = 0  # no .blend1 backups
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=False)
    return path
