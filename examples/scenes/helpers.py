# SPDX-License-Identifier: GPL-3.0-or-later
"""Building blocks of the example scenes: materials, meshes, camera, lights and world, made with bpy.

Every builder links what it makes into the current scene's collection.
"""

import math

import bpy  # must come before bmesh/mathutils: the bpy wheel puts them on the path
import bmesh  # noqa: I001
import numpy as np
from mathutils import Quaternion, Vector

# Checker texture colours (linear Rec.709).
CHECKER_A = (0.8, 0.8, 0.8)
CHECKER_B = (0.1, 0.3, 0.7)


def reset():
    """Empty the current Blender session (factory settings, no objects)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def diffuse_material(name, color):
    """Material with a single Diffuse BSDF of the given linear albedo."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    bsdf.location = (-300, 0)
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0)
    return mat


def emission_material(name, color, strength):
    """Material with a single Emission shader (no reflection)."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*color, 1.0)
    em.inputs["Strength"].default_value = strength
    em.location = (-300, 0)
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0)
    return mat


def mesh_object(name, verts, faces, material=None, uvs=None, smooth=False):
    """Create and link a mesh object from vertex/face lists.

    uvs: optional per-loop UVs, shape (n_loops, 2), in face-corner order.
    """
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(v) for v in verts], [], [tuple(f) for f in faces])
    if uvs is not None:
        layer = me.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", np.asarray(uvs, dtype=np.float32).ravel())
    if smooth:
        me.shade_smooth()
    me.update()
    if material is not None:
        me.materials.append(material)
    return link(bpy.data.objects.new(name, me))


def _oriented(corners, normal):
    """Return the 4 corners ordered so the quad's geometric normal is `normal`."""
    c = [Vector(p) for p in corners]
    n = (c[1] - c[0]).cross(c[3] - c[0])
    if n.dot(Vector(normal)) < 0:
        c = [c[0], c[3], c[2], c[1]]
    return c


def quad_faces(quads):
    """Stack quads given as (corners, normal[, uv_scale]) into verts/faces/uvs."""
    verts, faces, uvs = [], [], []
    for q in quads:
        corners, normal = q[0], q[1]
        s = q[2] if len(q) > 2 else 1.0
        c = _oriented(corners, normal)
        base = len(verts)
        verts.extend(c)
        faces.append((base, base + 1, base + 2, base + 3))
        uvs.extend([(0, 0), (s, 0), (s, s), (0, s)])
    return verts, faces, uvs


def quad(name, corners, normal, material, uv_scale=1.0):
    """A single-sided quad with its normal facing `normal`."""
    verts, faces, uvs = quad_faces([(corners, normal, uv_scale)])
    return mesh_object(name, verts, faces, material, uvs=uvs)


def box(name, size, location, rotation_z_deg=0.0, material=None):
    """Axis-aligned box of size (sx, sy, sz) centred at location, rotated about Z."""
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")
    bmesh.ops.create_cube(bm, size=1.0, calc_uvs=True)
    bmesh.ops.scale(bm, vec=Vector(size), verts=bm.verts)
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    if material is not None:
        me.materials.append(material)
    ob = link(bpy.data.objects.new(name, me))
    ob.location = location
    ob.rotation_euler = (0.0, 0.0, math.radians(rotation_z_deg))
    return ob


def uv_sphere(name, radius, location, material, segments=32, rings=16):
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=radius, calc_uvs=True)
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    me.shade_smooth()
    me.materials.append(material)
    ob = link(bpy.data.objects.new(name, me))
    ob.location = location
    return ob


def look_at_rotation(location, target, roll_deg=0.0):
    """Euler rotation that points an object's -Z at target with +Y up (then rolls)."""
    d = Vector(target) - Vector(location)
    q = d.to_track_quat("-Z", "Y")
    if roll_deg:
        q = q @ Quaternion((0.0, 0.0, 1.0), math.radians(roll_deg))
    return q.to_euler()


def camera(location, target=None, rotation=None, lens=35.0, roll_deg=0.0, name="Camera"):
    cam = bpy.data.cameras.new(name)
    cam.lens = lens
    cam.sensor_width = 36.0
    cam.sensor_height = 24.0
    cam.sensor_fit = "AUTO"
    cam.clip_start = 0.05
    cam.clip_end = 100.0
    ob = link(bpy.data.objects.new(name, cam))
    ob.location = location
    if target is not None:
        ob.rotation_euler = look_at_rotation(location, target, roll_deg)
    elif rotation is not None:
        ob.rotation_euler = rotation
    bpy.context.scene.camera = ob
    return ob


def light(name, kind, energy, location, rotation=None, target=None, color=(1.0, 1.0, 1.0), **props):
    """Create a light. Directional lights shine along their local -Z."""
    ld = bpy.data.lights.new(name, kind)
    ld.energy = energy
    ld.color = color
    for k, v in props.items():
        setattr(ld, k, v)
    ob = link(bpy.data.objects.new(name, ld))
    ob.location = location
    if target is not None:
        ob.rotation_euler = look_at_rotation(location, target)
    elif rotation is not None:
        ob.rotation_euler = rotation
    return ob


def set_world(color=(0.0, 0.0, 0.0), strength=0.0):
    world = bpy.data.worlds.new("World")
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = strength
    world.color = color
    bpy.context.scene.world = world
    return world


def checker_image(name="Checker", size=64, checks=2, colors=(CHECKER_A, CHECKER_B)):
    """Generated float checker image, Linear Rec.709 colourspace, packed.

    `checks` x `checks` squares; pixel (0, 0) is colours[0].
    Stored as a 32-bit float image so the linear values are exact.
    """
    img = bpy.data.images.new(name, size, size, alpha=False, float_buffer=True)
    img.colorspace_settings.name = "Linear Rec.709"
    cell = size // checks
    iy, ix = np.mgrid[0:size, 0:size]
    parity = ((ix // cell) + (iy // cell)) % 2
    px = np.empty((size, size, 4), dtype=np.float32)
    px[..., 3] = 1.0
    px[..., :3] = np.where(parity[..., None] == 0, colors[0], colors[1])
    img.pixels.foreach_set(px.ravel())
    img.update()
    img.pack()
    return img


def uv_image_node(nt, image):
    """An Image Texture node (repeat extension, linear filter) of `image` read through the "UVMap" UV map, in node
    tree `nt`; link its Color output where the image should go."""
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.extension = "REPEAT"
    tex.interpolation = "Linear"
    uv = nt.nodes.new("ShaderNodeUVMap")
    uv.uv_map = "UVMap"
    uv.location, tex.location = (-900, 0), (-650, 0)
    nt.links.new(uv.outputs["UV"], tex.inputs["Vector"])
    return tex


def textured_material(name, image):
    """UV-mapped Image Texture -> Diffuse BSDF (repeat extension, linear filter)."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Roughness"].default_value = 0.0
    bsdf.location = (-300, 0)
    nt.links.new(uv_image_node(nt, image).outputs["Color"], bsdf.inputs["Color"])
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mat.diffuse_color = (*np.mean([CHECKER_A, CHECKER_B], axis=0), 1.0)
    return mat


# Blender's default Principled BSDF (a new material's): base colour 0.8, roughness 0.5, IOR 1.5, Specular IOR Level 0.5.
DEFAULT_BASE = (0.8, 0.8, 0.8)
DEFAULT_ROUGHNESS = 0.5


def principled_material(name, color=DEFAULT_BASE, roughness=DEFAULT_ROUGHNESS, metallic=0.0, specular_level=None,
                        ior=None, emission=None, emission_strength=0.0, image=None):
    """Material with a single Principled BSDF; what is not given keeps Blender's default (IOR 1.5, Specular IOR
    Level 0.5, no emission). `image`: a UV-mapped Image Texture (repeat, linear) drives the base colour."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    bsdf = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    if specular_level is not None:
        bsdf.inputs["Specular IOR Level"].default_value = specular_level
    if ior is not None:
        bsdf.inputs["IOR"].default_value = ior
    if emission is not None:
        bsdf.inputs["Emission Color"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission_strength
    if image is not None:
        nt.links.new(uv_image_node(nt, image).outputs["Color"], bsdf.inputs["Base Color"])
    mat.diffuse_color = (*color, 1.0)
    return mat


def image_from_array(name, rgb):
    """Packed 32-bit float image, colourspace Linear Rec.709, from an (H, W, 3) array of linear colours whose row 0
    is the image's bottom row (Blender's order)."""
    rgb = np.asarray(rgb, np.float32)
    h, w = rgb.shape[:2]
    img = bpy.data.images.new(name, w, h, alpha=False, float_buffer=True)
    img.colorspace_settings.name = "Linear Rec.709"
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = rgb
    img.pixels.foreach_set(px.ravel())
    img.update()
    img.pack()
    return img


def cylinder(name, radius, depth, location, material, segments=24, caps=True, smooth=False):
    """A cylinder along Z centred at location; with caps it is closed (24 segments: 48 side and 2 x 22 cap
    triangles, 92 in all)."""
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")
    bmesh.ops.create_cone(bm, cap_ends=caps, cap_tris=False, segments=segments, radius1=radius, radius2=radius,
                          depth=depth, calc_uvs=True)
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    if smooth:
        me.shade_smooth()
    me.materials.append(material)
    ob = link(bpy.data.objects.new(name, me))
    ob.location = location
    return ob


def lathe(name, profile, location, material, segments=24):
    """A smooth surface of revolution about Z from a profile of (radius, z) points, bottom to top (a vase); the
    bottom is closed by a fan when its radius is > 0."""
    verts, faces = [], []
    n = len(profile)
    for r, z in profile:
        for k in range(segments):
            a = 2.0 * math.pi * k / segments
            verts.append((r * math.cos(a), r * math.sin(a), z))
    for i in range(n - 1):
        for k in range(segments):
            a, b = i * segments + k, i * segments + (k + 1) % segments
            faces.append((a, b, b + segments, a + segments))
    if profile[0][0] > 0:
        faces.append(tuple(reversed(range(segments))))
    ob = mesh_object(name, verts, faces, material, smooth=True)
    ob.location = location
    return ob
