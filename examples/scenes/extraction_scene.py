# SPDX-License-Identifier: GPL-3.0-or-later
"""The extraction scene: what the evaluated depsgraph adds over plain meshes (modifiers, collection instances,
custom split normals)."""

import math

import bpy  # must come before bmesh/mathutils: the bpy wheel puts them on the path
import bmesh  # noqa: I001
from mathutils import Matrix, Vector

from .helpers import box, camera, diffuse_material, light, link, mesh_object, quad, quad_faces
from .stage import STAGE_CUBE, STAGE_WHITE, SUN_ROTATION

CUSTOM_NORMAL = tuple(Vector((1.0, 0.0, 1.0)).normalized())


def extraction():
    """Modifiers, collection instances and custom split normals, lit by a sun.

    - "Blob": cube (mesh offset to x in [0.5, 1.5]) with a Mirror (X, about the
      object origin) then a Subdivision Surface modifier (levels 2 viewport and
      render): evaluates to two rounded blobs.
    - Collection "Props" (a "Cone" and a "Cylinder") is linked to the scene but
      EXCLUDED from the view layer; it is instanced 3 times by the Empties
      "PropsInstance.1..3" (different locations, rotations, scales).
    - "CustomNormals": a 2x2 m plane with every loop normal set to
      normalize(1, 0, 1) via normals_split_custom_set.
    - "Ground": 8x8 m floor so the scene has something to bounce off.
    """
    white = diffuse_material("White", STAGE_WHITE)
    quad("Ground", [(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], (0, 0, 1), white)
    _blob()
    _instanced_props()
    _custom_normals_plane()
    light("Sun", "SUN", 3.0, (0.0, 0.0, 5.0), rotation=SUN_ROTATION, angle=math.radians(0.5))
    camera((0.0, -8.0, 4.5), target=(0.0, 0.0, 0.4), lens=35.0)


def _blob():
    """Cube offset to x in [0.5, 1.5], mirrored about its origin in X, then subdivided (levels 2)."""
    blob = box("Blob", (1.0, 1.0, 1.0), (0.0, 1.0, 0.5), 0.0, diffuse_material("BlobBlue", (0.2, 0.3, 0.8)))
    blob.data.transform(Matrix.Translation((1.0, 0.0, 0.0)))
    mirror = blob.modifiers.new("Mirror", "MIRROR")
    mirror.use_axis[0] = True
    subsurf = blob.modifiers.new("Subdivision", "SUBSURF")
    subsurf.levels = 2
    subsurf.render_levels = 2


def _instanced_props():
    """Collection "Props" (Cone, Cylinder), excluded from the view layer, instanced by 3 Empties."""
    props = bpy.data.collections.new("Props")
    bpy.context.scene.collection.children.link(props)
    prop_mat = diffuse_material("PropsOrange", STAGE_CUBE)
    for name, op in (("Cone", bmesh.ops.create_cone), ("Cylinder", bmesh.ops.create_cone)):
        bm = bmesh.new()
        bm.loops.layers.uv.new("UVMap")
        r2 = 0.0 if name == "Cone" else 0.3
        op(bm, cap_ends=True, segments=24, radius1=0.3, radius2=r2, depth=0.8, calc_uvs=True)
        bmesh.ops.translate(bm, vec=(0.0, 0.0, 0.4), verts=bm.verts)  # base on z=0
        me = bpy.data.meshes.new(name)
        bm.to_mesh(me)
        bm.free()
        me.materials.append(prop_mat)
        ob = bpy.data.objects.new(name, me)
        ob.location = (0.0, 0.0, 0.0) if name == "Cone" else (0.7, 0.0, 0.0)
        props.objects.link(ob)
    bpy.context.view_layer.layer_collection.children["Props"].exclude = True

    placements = [
        ((-2.0, -1.0, 0.0), (0.0, 0.0, 0.0), 1.0),
        ((-2.5, 1.5, 0.0), (0.0, 0.0, math.radians(45.0)), 1.5),
        ((2.0, -1.5, 0.0), (0.0, 0.0, math.radians(-60.0)), 0.7),
    ]
    for i, (loc, rot, scale) in enumerate(placements, 1):
        empty = link(bpy.data.objects.new(f"PropsInstance.{i}", None))
        empty.instance_type = "COLLECTION"
        empty.instance_collection = props
        empty.location, empty.rotation_euler, empty.scale = loc, rot, (scale,) * 3


def _custom_normals_plane():
    """A 2x2 m plane with every loop normal set to CUSTOM_NORMAL."""
    verts, faces, uvs = quad_faces([([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], (0, 0, 1))])
    plane = mesh_object("CustomNormals", verts, faces, diffuse_material("Grey", (0.5, 0.5, 0.5)), uvs=uvs)
    plane.location = (0.5, -2.0, 0.6)
    plane.data.normals_split_custom_set([CUSTOM_NORMAL] * len(plane.data.loops))
