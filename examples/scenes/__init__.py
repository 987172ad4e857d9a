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
textured, principled, camera_*), extraction_scene.py (extraction),
rooms.py (spot_room, courtyard), animated.py (cornell_animated: a
change per frame), and the scenes like users' (USER_SCENES, checked
against committed Cycles references): users.py (default_principled,
metals, many_lights, outdoor, product_shot) and interiors.py
(window_room, rug_room, thin_walls, lamp_room, furnished). This module holds the registry, build()
and save(), and re-exports the public names of those modules, so
`scenes.<name>` reaches all of them.
"""

import bpy  # must come before bmesh/mathutils: the bpy wheel puts them on the path

from .animated import ANIMATED_FRAMES, cornell_animated
from .cornell_box import (CORNELL_EMISSION_STRENGTH, CORNELL_GREEN, CORNELL_LIGHT_POWER,
                          CORNELL_LIGHT_SIZE, CORNELL_RED, CORNELL_WHITE, cornell, cornell_emissive)
from .extraction_scene import CUSTOM_NORMAL, extraction
from .helpers import (CHECKER_A, CHECKER_B, DEFAULT_BASE, DEFAULT_ROUGHNESS, box, camera, checker_image, cylinder,
                      diffuse_material, emission_material, image_from_array, lathe, light, look_at_rotation,
                      mesh_object, principled_material, quad, quad_faces, reset, set_world, textured_material,
                      uv_sphere)
from .interiors import (LAMP_SHADE, RUG_HEIGHT, THIN_WALL, furnished, lamp_room, rug_room, thin_walls,
                        window_room)
from .rooms import COURTYARD_OPENING, COURTYARD_SUN_ROTATION, courtyard, spot_room
from .stage import (AREA_LOCATION, AREA_ROTATION, CUBE_LOCATION, POINT_LOCATION, SPOT_LOCATION,
                    STAGE_CUBE, STAGE_WHITE, SUN_ROTATION, camera_ortho, camera_shift, light_area_disk,
                    light_area_square, light_mixed, light_point, light_point_soft, light_spot, light_sun,
                    principled, textured)
from .users import BRASS, SKY, default_principled, many_lights, metals, outdoor, product_shot

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
           "SCENES", "build", "save",
           "DEFAULT_BASE", "DEFAULT_ROUGHNESS", "cylinder", "image_from_array", "lathe", "LAMP_SHADE", "RUG_HEIGHT",
           "THIN_WALL", "furnished", "lamp_room", "rug_room", "thin_walls", "window_room", "BRASS", "SKY",
           "default_principled", "many_lights", "metals", "outdoor", "product_shot", "USER_SCENES"]


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
    # Scenes like users' (users.py, interiors.py), checked against committed Cycles references
    "default_principled": default_principled,
    "metals": metals,
    "window_room": window_room,
    "rug_room": rug_room,
    "thin_walls": thin_walls,
    "lamp_room": lamp_room,
    "many_lights": many_lights,
    "outdoor": outdoor,
    "product_shot": product_shot,
    "furnished": furnished,
}

# The example set like users' scenes (issue 17): what each covers. Every one has a committed Cycles reference
# (examples/references/) and is checked against it by tests/accuracy/test_examples_vs_cycles.py.
USER_SCENES = {
    "default_principled": "Blender's default Principled BSDF on every surface, a brass vase (metallic 1)",
    "metals": "metals: gold, copper, steel, aluminium at several roughnesses",
    "textured": "an image texture (a checker floor)",
    "window_room": "a room with a window, lit by sun and sky (world strength 1, constant colour)",
    "rug_room": "a coloured rug 1 mm above a white floor (and a poster 1 mm off a wall), spot-lit",
    "thin_walls": "two rooms behind walls 2 cm thick (thinner than a voxel), sun and sky through one window",
    "lamp_room": "an emissive lamp: a closed cylinder shade (Principled emission) lights a room",
    "many_lights": "20 point lights in a hall",
    "outdoor": "a town block 200 m across under sun and sky",
    "product_shot": "a product shot 10 cm across",
    "furnished": "a furnished living room: 40 objects, textures, sun, sky, an area light, an emissive shade",
    "cornell_animated": "an animated scene (the reference is frame 4, where every kind of change has happened)",
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
