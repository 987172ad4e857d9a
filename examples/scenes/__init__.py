"""Example scenes for Bounce GI, built in code with bpy.

Used by the demo, the tests (comparisons against Cycles) and benchmarks.
Units are metres, Z up. Every scene has exactly one camera, renders at
160x120 by default, and has a black world (strength 0) unless stated.

    from examples import scenes
    scenes.build("cornell")            # replaces the current bpy data
    scenes.save("cornell", "/tmp/cornell.blend")

Materials are Diffuse BSDF (exact albedo, design.md section 3) with the
viewport display colour set to the same albedo, unless a scene says
otherwise. Image textures are generated in code and packed into the .blend.
"""

import math

import bpy  # must come before bmesh/mathutils: the bpy wheel puts them on the path
import bmesh  # noqa: I001
import numpy as np
from mathutils import Matrix, Quaternion, Vector

RESOLUTION = (160, 120)

# Colours (linear Rec.709).
CORNELL_WHITE = (0.725, 0.71, 0.68)
CORNELL_RED = (0.63, 0.065, 0.05)
CORNELL_GREEN = (0.14, 0.45, 0.091)
STAGE_WHITE = (0.8, 0.8, 0.8)
STAGE_CUBE = (0.8, 0.3, 0.2)
CHECKER_A = (0.8, 0.8, 0.8)
CHECKER_B = (0.1, 0.3, 0.7)

# Stage light placements, shared by the single-light scenes and light_mixed.
SUN_ROTATION = (math.radians(45.0), 0.0, math.radians(-30.0))
POINT_LOCATION = (1.5, -1.5, 3.0)
SPOT_LOCATION = (-1.0, -2.5, 3.5)
CUBE_LOCATION = (-1.0, 0.0, 0.5)
AREA_LOCATION = (0.0, -1.0, 3.0)
AREA_ROTATION = (math.radians(20.0), 0.0, 0.0)  # faces down, tilted towards the back wall


# --------------------------------------------------------------------------- helpers


def reset():
    """Empty the current Blender session (factory settings, no objects)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)


def _link(obj):
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
    return _link(bpy.data.objects.new(name, me))


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
    ob = _link(bpy.data.objects.new(name, me))
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
    ob = _link(bpy.data.objects.new(name, me))
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
    ob = _link(bpy.data.objects.new(name, cam))
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
    ob = _link(bpy.data.objects.new(name, ld))
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


def textured_material(name, image):
    """UV-mapped Image Texture -> Diffuse BSDF (repeat extension, linear filter)."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Roughness"].default_value = 0.0
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.extension = "REPEAT"
    tex.interpolation = "Linear"
    uv = nt.nodes.new("ShaderNodeUVMap")
    uv.uv_map = "UVMap"
    uv.location, tex.location, bsdf.location = (-900, 0), (-650, 0), (-300, 0)
    nt.links.new(uv.outputs["UV"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Color"])
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mat.diffuse_color = (*np.mean([CHECKER_A, CHECKER_B], axis=0), 1.0)
    return mat


# --------------------------------------------------------------------------- Cornell box


def _cornell_geometry(ceiling_hole=0.0):
    """Walls, boxes and camera. ceiling_hole > 0 leaves a centred square opening
    of that size in the ceiling (for a flush emissive panel)."""
    white = diffuse_material("White", CORNELL_WHITE)
    red = diffuse_material("Red", CORNELL_RED)
    green = diffuse_material("Green", CORNELL_GREEN)
    x0, x1, y0, y1, z0, z1 = -1.0, 1.0, -1.0, 1.0, 0.0, 2.0
    quad("Floor", [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, 1), white)
    if ceiling_hole > 0:
        h = ceiling_hole / 2
        rects = [(x0, x1, h, y1), (x0, x1, y0, -h), (x0, -h, -h, h), (h, x1, -h, h)]
        verts, faces, uvs = quad_faces(
            [([(a, c, z1), (b, c, z1), (b, d, z1), (a, d, z1)], (0, 0, -1)) for a, b, c, d in rects]
        )
        mesh_object("Ceiling", verts, faces, white, uvs=uvs)
    else:
        quad("Ceiling", [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1), white)
    quad("BackWall", [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, -1, 0), white)
    quad("LeftWall", [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (1, 0, 0), red)
    quad("RightWall", [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (-1, 0, 0), green)
    # Proportions of the classic box (552.8 units -> 2 m).
    box("TallBox", (0.6, 0.6, 1.2), (-0.33, 0.28, 0.6), 17.0, white)
    box("ShortBox", (0.6, 0.6, 0.6), (0.34, -0.32, 0.3), -17.0, white)
    camera((0.0, -3.9, 1.0), rotation=(math.radians(90.0), 0.0, 0.0), lens=38.0)


CORNELL_LIGHT_SIZE = 0.5
CORNELL_LIGHT_POWER = 60.0
# Cycles: an area light of power P and area A has radiance P / (pi * A); an
# Emission shader of strength S has radiance S. So 60 W over 0.25 m^2 matches
# strength 240 / pi = 76.39. The emissive scene uses 10 (as specified), i.e.
# 7.64x dimmer than `cornell`.
CORNELL_EMISSION_STRENGTH = 10.0


def cornell():
    """Classic Cornell box lit by a 0.5 m square area light, 60 W, at z=1.98 facing down."""
    _cornell_geometry()
    light(
        "AreaLight", "AREA", CORNELL_LIGHT_POWER, (0.0, 0.0, 1.98), rotation=(0.0, 0.0, 0.0),
        shape="SQUARE", size=CORNELL_LIGHT_SIZE,
    )


def cornell_emissive():
    """Cornell box lit by an emissive 0.5 m quad (Emission, white, strength 10).

    The panel sits flush in a matching opening of the ceiling (z=2, facing
    down), so the light Cycles emits from its back side leaves the box and the
    panel acts as a one-sided emitter with zero albedo.
    """
    _cornell_geometry(ceiling_hole=CORNELL_LIGHT_SIZE)
    h = CORNELL_LIGHT_SIZE / 2
    z = 2.0
    quad(
        "LightPanel",
        [(-h, -h, z), (h, -h, z), (h, h, z), (-h, h, z)],
        (0, 0, -1),
        emission_material("Emitter", (1.0, 1.0, 1.0), CORNELL_EMISSION_STRENGTH),
    )


# --------------------------------------------------------------------------- stage


def _stage(floor_material=None, floor_uv_scale=1.0):
    """Floor 6x6 m, back wall at y=2, a rotated cube and a smooth UV sphere; camera."""
    white = diffuse_material("White", STAGE_WHITE)
    floor_mat = floor_material or white
    quad("Floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1), floor_mat, floor_uv_scale)
    quad("BackWall", [(-3, 2, 0), (3, 2, 0), (3, 2, 3), (-3, 2, 3)], (0, -1, 0), white)
    box("Cube", (1.0, 1.0, 1.0), CUBE_LOCATION, 30.0, diffuse_material("CubeOrange", STAGE_CUBE))
    uv_sphere("Sphere", 0.6, (1.2, -0.3, 0.6), white)


def _stage_camera():
    return camera((0.0, -7.0, 3.2), target=(0.0, 0.0, 0.7), lens=35.0)


def _sun(strength=3.0):
    return light("Sun", "SUN", strength, (0.0, 0.0, 5.0), rotation=SUN_ROTATION, angle=math.radians(0.5))


def _point(power=500.0, radius=0.0, name="PointLight"):
    return light(name, "POINT", power, POINT_LOCATION, shadow_soft_size=radius)


def _spot(power=800.0):
    return light(
        "SpotLight", "SPOT", power, SPOT_LOCATION, target=CUBE_LOCATION,
        spot_size=math.radians(60.0), spot_blend=0.3, shadow_soft_size=0.0,
    )


def _area(power=300.0, shape="SQUARE", size=1.0, name="AreaLight"):
    return light(name, "AREA", power, AREA_LOCATION, rotation=AREA_ROTATION, shape=shape, size=size)


def light_sun():
    """Stage lit by a sun, 3 W/m2, angle 0.5 deg, from the upper left."""
    _stage()
    _stage_camera()
    _sun()


def light_point():
    """Stage lit by a 500 W point light with zero radius (hard shadows)."""
    _stage()
    _stage_camera()
    _point()


def light_point_soft():
    """Stage lit by a 500 W point light with radius 0.25 m (soft shadows)."""
    _stage()
    _stage_camera()
    _point(radius=0.25)


def light_spot():
    """Stage lit by an 800 W spot (60 deg, blend 0.3, radius 0) aimed at the cube."""
    _stage()
    _stage_camera()
    _spot()


def light_area_square():
    """Stage lit by a 1 m square area light, 300 W, tilted 20 deg towards the back wall."""
    _stage()
    _stage_camera()
    _area()


def light_area_disk():
    """Stage lit by a 1.2 m diameter disk area light, 300 W, placed like the square one."""
    _stage()
    _stage_camera()
    _area(shape="DISK", size=1.2)


def light_mixed():
    """Stage with sun 1 W/m2 + point 200 W + spot 400 W + square area 150 W."""
    _stage()
    _stage_camera()
    _sun(1.0)
    _point(200.0)
    _spot(400.0)
    _area(150.0)


def textured():
    """Stage with a checker-textured floor (6x6 checks) lit by the sun.

    The image is 64x64 with 2x2 checks, 32-bit float, colourspace Linear
    Rec.709 (pixel values are the linear albedos), packed; the floor UVs run
    0..3 with REPEAT extension, so the floor shows 6x6 checks.
    """
    img = checker_image()
    _stage(floor_material=textured_material("Checker", img), floor_uv_scale=3.0)
    _stage_camera()
    _sun()


def principled_material(name, color, roughness, metallic=0.0):
    """Material with a single Principled BSDF (IOR 1.5, Specular IOR Level 0.5 — Blender's defaults)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    mat.diffuse_color = (*color, 1.0)
    return mat


def principled():
    """Stage with Principled BSDF materials (rough floor, glossy sphere, half-metallic cube), lit by the sun.

    Checks the view-dependent Diffuse Color of Principled BSDF (its specular layer takes a share of the base).
    """
    quad("Floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1),
         principled_material("RoughFloor", STAGE_WHITE, 0.8))
    quad("BackWall", [(-3, 2, 0), (3, 2, 0), (3, 2, 3), (-3, 2, 3)], (0, -1, 0),
         principled_material("Wall", STAGE_WHITE, 0.5))
    box("Cube", (1.0, 1.0, 1.0), CUBE_LOCATION, 30.0, principled_material("HalfMetal", STAGE_CUBE, 0.4, 0.5))
    uv_sphere("Sphere", 0.6, (1.2, -0.3, 0.6), principled_material("Glossy", STAGE_WHITE, 0.2))
    _stage_camera()
    _sun()


def camera_shift():
    """Stage with a sun; camera rolled 15 deg, shift (0.1, -0.05), sensor fit VERTICAL."""
    _stage()
    _sun()
    cam = camera((0.0, -7.0, 3.2), target=(0.0, 0.0, 0.7), lens=35.0, roll_deg=15.0)
    cam.data.shift_x = 0.1
    cam.data.shift_y = -0.05
    cam.data.sensor_fit = "VERTICAL"


def camera_ortho():
    """Stage with a sun; orthographic camera (ortho_scale 8) looking down at 45 deg."""
    _stage()
    _sun()
    target = Vector((0.0, 0.0, 0.7))
    loc = target + 10.0 * Vector((0.0, -math.cos(math.radians(45)), math.sin(math.radians(45))))
    cam = camera(tuple(loc), target=tuple(target))
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = 8.0


# --------------------------------------------------------------------------- extraction


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

    blob = box("Blob", (1.0, 1.0, 1.0), (0.0, 1.0, 0.5), 0.0, diffuse_material("BlobBlue", (0.2, 0.3, 0.8)))
    blob.data.transform(Matrix.Translation((1.0, 0.0, 0.0)))
    mirror = blob.modifiers.new("Mirror", "MIRROR")
    mirror.use_axis[0] = True
    subsurf = blob.modifiers.new("Subdivision", "SUBSURF")
    subsurf.levels = 2
    subsurf.render_levels = 2

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
        empty = _link(bpy.data.objects.new(f"PropsInstance.{i}", None))
        empty.instance_type = "COLLECTION"
        empty.instance_collection = props
        empty.location, empty.rotation_euler, empty.scale = loc, rot, (scale,) * 3

    verts, faces, uvs = quad_faces([([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], (0, 0, 1))])
    plane = mesh_object("CustomNormals", verts, faces, diffuse_material("Grey", (0.5, 0.5, 0.5)), uvs=uvs)
    plane.location = (0.5, -2.0, 0.6)
    plane.data.normals_split_custom_set([CUSTOM_NORMAL] * len(plane.data.loops))

    light("Sun", "SUN", 3.0, (0.0, 0.0, 5.0), rotation=SUN_ROTATION, angle=math.radians(0.5))
    camera((0.0, -8.0, 4.5), target=(0.0, 0.0, 0.4), lens=35.0)


# --------------------------------------------------------------------------- GI rooms


def _room(name_prefix, x0, x1, y0, y1, z0, z1, mats, skip=()):
    """Inward-facing axis-aligned room quads; mats maps wall name -> material."""
    walls = {
        "Floor": ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, 1)),
        "Ceiling": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1)),
        "BackWall": ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, -1, 0)),
        "FrontWall": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, 1, 0)),
        "LeftWall": ([(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (1, 0, 0)),
        "RightWall": ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (-1, 0, 0)),
    }
    for wname, (corners, normal) in walls.items():
        if wname not in skip:
            quad(name_prefix + wname, corners, normal, mats[wname])


def spot_room():
    """Closed 4x4x2.6 m room, white (0.7) with a red right wall, a box, a 600 W
    ceiling spot (70 deg) pointing straight down; camera inside near the front wall."""
    white = diffuse_material("White", (0.7, 0.7, 0.7))
    red = diffuse_material("Red", (0.7, 0.15, 0.1))
    mats = {k: white for k in ("Floor", "Ceiling", "BackWall", "FrontWall", "LeftWall")}
    mats["RightWall"] = red
    _room("", -2.0, 2.0, -2.0, 2.0, 0.0, 2.6, mats)
    box("Box", (0.7, 0.7, 0.7), (0.9, 0.6, 0.35), 20.0, white)
    light(
        "SpotLight", "SPOT", 600.0, (0.0, 0.3, 2.55), rotation=(0.0, 0.0, 0.0),
        spot_size=math.radians(70.0), spot_blend=0.15, shadow_soft_size=0.0,
    )
    camera((-0.3, -1.85, 1.5), target=(0.2, 0.6, 0.5), lens=18.0)


COURTYARD_OPENING = (-1.0, 2.0, -2.5, 0.0)  # roof hole x0, x1, y0, y1 at z=3 (3 x 2.5 m)
COURTYARD_SUN_ROTATION = (math.radians(30.0), 0.0, math.radians(30.0))


def courtyard():
    """6x6 m courtyard, 3 m walls, roof with a 3x2.5 m opening; sun (5 W/m2) enters
    through the opening and lights a patch of floor, the rest is bounce light only."""
    white = diffuse_material("White", (0.7, 0.7, 0.7))
    mats = {k: white for k in ("Floor", "BackWall", "FrontWall", "LeftWall", "RightWall")}
    _room("", -3.0, 3.0, -3.0, 3.0, 0.0, 3.0, mats, skip=("Ceiling",))
    # Roof: four rectangles around the opening, one mesh, facing down (inward).
    ox0, ox1, oy0, oy1 = COURTYARD_OPENING
    z = 3.0
    rects = [
        (-3.0, 3.0, oy1, 3.0),  # behind the opening
        (-3.0, 3.0, -3.0, oy0),  # in front
        (-3.0, ox0, oy0, oy1),  # left
        (ox1, 3.0, oy0, oy1),  # right
    ]
    verts, faces, uvs = quad_faces(
        [([(a, c, z), (b, c, z), (b, d, z), (a, d, z)], (0, 0, -1)) for a, b, c, d in rects]
    )
    mesh_object("Roof", verts, faces, white, uvs=uvs)
    light("Sun", "SUN", 5.0, (0.0, 0.0, 6.0), rotation=COURTYARD_SUN_ROTATION, angle=math.radians(0.5))
    camera((2.7, -2.7, 1.4), target=(-0.6, 0.8, 0.7), lens=16.0)


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
