# SPDX-License-Identifier: GPL-3.0-or-later
"""Scenes lit by emissive meshes only, for tests/accuracy/test_emitters_vs_cycles.py (issue 17: every emissive
triangle shadowed, emission counted once). Built with bpy from examples/scenes/helpers.py's pieces, but kept out of
the example registry: they are test cases, not examples.

- `lamp_room`: a closed 4 × 4 × 2.6 m room with furniture, lit only by a closed emissive lamp shade hanging in it
  (a capped 24-segment cylinder, 92 triangles, an Emission shader: no albedo, light from both sides as in Cycles).
  The light emitted inside the shade never leaves it.
- `lamp_room_open`: the same room with the shade plus an open emitter: a bent two-sided emissive strip (three
  quads at angles) standing on the cabinet, whose both sides light the room.

- `lamp_room_albedo`: the shade reflects too (diffuse albedo 0.8 under its emission).

compare_examples.py builds them by the name `tests.support.emitter_scenes:<function>`.
"""
import math

import bmesh
import bpy
from mathutils import Vector

from examples.scenes.helpers import (box, camera, diffuse_material, emission_material, link, mesh_object, quad,
                                     reset, set_world)

RESOLUTION = (160, 120)
SHADE_SEGMENTS = 24  # 24 side quads (48 triangles) + two 22-triangle caps = 92 triangles, as in the issue
SHADE_RADIUS, SHADE_HEIGHT, SHADE_CENTRE = 0.22, 0.32, (0.3, 0.4, 1.55)
SHADE_STRENGTH = 12.0


def _room(white, red, blue):
    x0, x1, y0, y1, z0, z1 = -2.0, 2.0, -2.0, 2.0, 0.0, 2.6
    walls = {
        "Floor": ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, 1), white),
        "Ceiling": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1), white),
        "BackWall": ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, -1, 0), white),
        "FrontWall": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, 1, 0), white),
        "LeftWall": ([(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (1, 0, 0), red),
        "RightWall": ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (-1, 0, 0), blue),
    }
    for name, (corners, normal, mat) in walls.items():
        quad(name, corners, normal, mat)


def _furniture(white, wood):
    box("TableTop", (1.2, 0.7, 0.05), (0.2, 0.5, 0.75), 10.0, wood)
    for i, (dx, dy) in enumerate(((-0.5, -0.28), (0.5, -0.28), (-0.5, 0.28), (0.5, 0.28))):
        c, s = math.cos(math.radians(10)), math.sin(math.radians(10))
        box(f"Leg{i}", (0.06, 0.06, 0.72), (0.2 + c * dx - s * dy, 0.5 + s * dx + c * dy, 0.36), 10.0, wood)
    box("Cabinet", (0.5, 1.4, 0.9), (-1.7, 0.6, 0.45), 0.0, white)
    box("Sofa", (1.6, 0.7, 0.45), (0.6, -1.4, 0.225), -5.0, wood)
    box("Shelf", (0.9, 0.3, 1.6), (1.5, 1.7, 0.8), 0.0, white)


def closed_cylinder(name, radius, height, location, segments, material):
    """A capped cylinder (bmesh.create_cone with both caps as n-gons, triangulated on extraction)."""
    bm = bmesh.new()
    bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=segments, radius1=radius, radius2=radius,
                          depth=height)
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    me.materials.append(material)
    ob = link(bpy.data.objects.new(name, me))
    ob.location = location
    return ob


def _shade():
    mat = emission_material("ShadeEmission", (1.0, 0.85, 0.6), SHADE_STRENGTH)
    return closed_cylinder("LampShade", SHADE_RADIUS, SHADE_HEIGHT, SHADE_CENTRE, SHADE_SEGMENTS, mat)


def _camera():
    camera((-1.2, -1.85, 1.45), target=(0.4, 0.6, 0.9), lens=17.0)


def _base():
    white = diffuse_material("White", (0.75, 0.75, 0.75))
    red = diffuse_material("Red", (0.7, 0.2, 0.12))
    blue = diffuse_material("Blue", (0.15, 0.3, 0.65))
    wood = diffuse_material("Wood", (0.55, 0.38, 0.22))
    _room(white, red, blue)
    _furniture(white, wood)
    _camera()


def lamp_room():
    """The furnished room lit by the closed lamp shade alone."""
    _base()
    _shade()


def lamp_room_open():
    """The room lit by the closed shade and an open two-sided emissive strip on the cabinet."""
    _base()
    _shade()
    strip = emission_material("StripEmission", (0.6, 0.8, 1.0), 6.0)
    x, y, z0, z1 = -1.55, 0.6, 0.9, 1.5
    pts = [Vector((x, y - 0.55, 0)), Vector((x + 0.12, y - 0.2, 0)), Vector((x + 0.12, y + 0.2, 0)),
           Vector((x, y + 0.55, 0))]
    verts = [(p.x, p.y, z0) for p in pts] + [(p.x, p.y, z1) for p in pts]
    faces = [(i, i + 1, i + 5, i + 4) for i in range(3)]
    mesh_object("Strip", verts, faces, strip)


def lamp_room_albedo():
    """The room lit by a closed shade that also reflects: a Principled BSDF (base colour 0.8, Specular IOR Level 0,
    so purely diffuse) with the same emission. Its inside is lit by its own emission and keeps that light."""
    _base()
    mat = bpy.data.materials.new("ShadePrincipled")
    mat.use_nodes = True
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (0.8, 0.8, 0.8, 1.0)
    bsdf.inputs["Roughness"].default_value = 1.0
    bsdf.inputs["Specular IOR Level"].default_value = 0.0
    bsdf.inputs["Emission Color"].default_value = (1.0, 0.85, 0.6, 1.0)
    bsdf.inputs["Emission Strength"].default_value = SHADE_STRENGTH
    mat.diffuse_color = (0.8, 0.8, 0.8, 1.0)
    closed_cylinder("LampShade", SHADE_RADIUS, SHADE_HEIGHT, SHADE_CENTRE, SHADE_SEGMENTS, mat)


def build(name):
    """Reset Blender and build `name` (a function of this module) like examples.scenes.build."""
    reset()
    scene = bpy.context.scene
    scene.name = name
    set_world()
    globals()[name]()
    scene.render.resolution_x, scene.render.resolution_y = RESOLUTION
    scene.render.resolution_percentage = 100
    scene.frame_set(1)
    bpy.context.view_layer.update()
