# SPDX-License-Identifier: GPL-3.0-or-later
"""Random scenes built in Blender for tests/stress/test_random_blender.py.

A spec (plain JSON, drawn by hypothesis in the test process) becomes real bpy data: meshes made with bmesh and
`Mesh.from_pydata`, Principled / Diffuse / Emission materials, lights, a world, a camera, every length × 10^scale and
point / spot / area power × scale²; and the bad input a user can make: a zero-area face, a face duplicated and a
flipped copy of it, an object with a NaN vertex. The scene then goes through the add-on's own `extract_scene`.

bpy stays out of the pytest process (tests/conftest.py, test_camera.py): `BpyWorker` starts this file as a script
once and sends it one request per line; the script resets Blender to an empty file, builds the spec, extracts it and
pickles (Scene, what bpy itself counts) into the file the request names, then answers on one stdout line.
"""
import json
import math
import os
import pickle
import subprocess
import sys
import traceback

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REPLY = "RANDOM_BPY "  # the prefix of the worker's answer (Blender prints lines of its own on stdout)
RESOLUTION = (32, 24)
ROOM_HALF = 3.0  # the optional room: a closed box of side 6 (× scale) around every object (coordinates in ±2)


class BpyWorker:
    """The test process's end: one bpy subprocess for many scenes (starting bpy costs ~1 s, a scene ~0.1 s)."""

    def __init__(self, tmp_dir):
        self.tmp = str(tmp_dir)
        self.log = open(os.path.join(self.tmp, "worker.log"), "w+")
        env = {**os.environ, "BLENDER_USER_RESOURCES": os.path.join(self.tmp, "blender_user")}
        self.proc = subprocess.Popen([sys.executable, os.path.abspath(__file__)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=self.log, text=True, cwd=ROOT, env=env)

    def extract(self, spec: dict):
        """(the extracted Scene, {"triangles": {object: n}, "finite": {object: bool}} as bpy counts them); raises
        AssertionError with the worker's traceback where building or extracting raised."""
        out = os.path.join(self.tmp, "scene.pickle")
        self.proc.stdin.write(json.dumps({"spec": spec, "out": out}) + "\n")
        self.proc.stdin.flush()
        for line in self.proc.stdout:
            if line.startswith(REPLY):
                reply = json.loads(line[len(REPLY):])
                break
        else:
            self.log.seek(0)
            raise RuntimeError(f"the bpy worker exited ({self.proc.wait()}):\n{self.log.read()[-3000:]}")
        assert reply["ok"], f"building or extracting in Blender raised:\n{reply['error']}"
        with open(out, "rb") as f:
            return pickle.load(f)

    def close(self):
        self.proc.stdin.close()
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.log.close()


# --- the bpy side (run as a script) --------------------------------------------------------------------------------

def serve():
    import bpy  # noqa: F401  (before bmesh and mathutils)

    from bounce_gi.addon.extract import extract_scene

    for line in sys.stdin:
        request = json.loads(line)
        try:
            counted = build(request["spec"])
            scene = extract_scene(bpy.context.evaluated_depsgraph_get())
            with open(request["out"], "wb") as f:
                pickle.dump((scene, counted), f)
            reply = {"ok": True}
        except Exception:
            reply = {"ok": False, "error": traceback.format_exc()}
        print(REPLY + json.dumps(reply), flush=True)


def build(spec: dict) -> dict:
    """Reset Blender to an empty file and build `spec` in it; returns what bpy counts of each mesh object."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = RESOLUTION
    scene.render.resolution_percentage = 100
    s = 10.0 ** spec["scale"]
    mats = [make_material(f"Mat{i}", m) for i, m in enumerate(spec["materials"])]
    for i, o in enumerate(spec["objects"]):
        add_shape(f"Mesh{i}", o, mats[o["material"] % len(mats)], s)
    if spec["room"]:
        room = {"shape": "cube", "at": (0, 0, 0), "size": (2 * ROOM_HALF,) * 3, "rot": (0, 0, 0), "inward": True,
                "object_scale": False, "smooth": False}
        add_shape("Room", room, mats[-1], s)
    add_bad_objects(spec["bad"], mats[0], s)
    for i, lamp in enumerate(spec["lights"]):
        add_light(f"Light{i}", lamp, s)
    set_world(spec["world"])
    add_camera(spec["camera"], s)
    return count_meshes()


def link(name, data, at=(0.0, 0.0, 0.0), rot=(0.0, 0.0, 0.0), s=1.0):
    import bpy

    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = [c * s for c in at]
    obj.rotation_euler = rot
    return obj


def make_material(name: str, m: dict):
    """A Principled BSDF (colour, roughness, metallic, emission), a Diffuse BSDF or an Emission shader."""
    import bpy

    mat = bpy.data.materials.new(name)
    tree = mat.node_tree
    color = (*m["color"], 1.0)
    if m["kind"] == "PRINCIPLED":
        node = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        node.inputs["Base Color"].default_value = color
        node.inputs["Roughness"].default_value = m["roughness"]
        node.inputs["Metallic"].default_value = m["metallic"]
        node.inputs["Emission Color"].default_value = color
        node.inputs["Emission Strength"].default_value = m["emission"]
        return mat
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    if m["kind"] == "DIFFUSE":
        node = tree.nodes.new("ShaderNodeBsdfDiffuse")
        node.inputs["Color"].default_value = color
        node.inputs["Roughness"].default_value = m["roughness"]
    else:
        node = tree.nodes.new("ShaderNodeEmission")
        node.inputs["Color"].default_value = color
        node.inputs["Strength"].default_value = m["emission"]
    tree.links.new(node.outputs[0], out.inputs["Surface"])
    return mat


def shape_mesh(name: str, shape: str, inward: bool):
    """A unit-sized mesh: bmesh primitives, or a tetrahedron through from_pydata; faces reversed when `inward`."""
    import bmesh
    import bpy

    me = bpy.data.meshes.new(name)
    if shape == "tetra":
        me.from_pydata([(0.5, 0.5, 0.5), (0.5, -0.5, -0.5), (-0.5, 0.5, -0.5), (-0.5, -0.5, 0.5)], [],
                       [(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)])
    bm = bmesh.new()
    if shape == "tetra":
        bm.from_mesh(me)
    elif shape == "cube":
        bmesh.ops.create_cube(bm, size=1.0)
    elif shape == "ico":
        bmesh.ops.create_icosphere(bm, subdivisions=1, radius=0.5)
    elif shape == "cylinder":
        bmesh.ops.create_cone(bm, cap_ends=True, segments=8, radius1=0.5, radius2=0.5, depth=1.0)
    else:
        bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=0.5)
    if inward:
        bmesh.ops.reverse_faces(bm, faces=bm.faces)
    bm.to_mesh(me)
    bm.free()
    return me


def add_shape(name: str, o: dict, mat, s: float):
    """A mesh object; its size (× scale) either in the object's scale or in the mesh's vertices."""
    from mathutils import Matrix

    me = shape_mesh(name, o["shape"], o["inward"])
    size = [c * s for c in o["size"]]
    if not o["object_scale"]:
        me.transform(Matrix.Diagonal((*size, 1.0)))
    if o["smooth"]:
        me.shade_smooth()
    me.materials.append(mat)
    obj = link(name, me, o["at"], o["rot"], s)
    if o["object_scale"]:
        obj.scale = size
    return obj


def pydata_object(name: str, verts, faces, mat, at, s: float):
    import bpy

    me = bpy.data.meshes.new(name)
    me.from_pydata([[c * s for c in v] for v in verts], [], faces)
    me.materials.append(mat)
    return link(name, me, at, s=s)


def add_bad_objects(bad: dict, mat, s: float) -> None:
    """ZeroArea: a triangle with collinear corners and a quad scaled to a point (S 0); Doubled: a quad, the same
    quad again and a flipped copy (an import's overlapping faces); Broken: a cube with one NaN vertex."""
    if bad["zero_area"]:
        verts = [(0, 0, 0), (0.5, 0, 0), (1, 0, 0)] + [(0.3, 0.2, 0.1)] * 4
        pydata_object("ZeroArea", verts, [(0, 1, 2), (3, 4, 5, 6)], mat, bad["at"], s)
    if bad["doubled"]:
        verts = [(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)]
        pydata_object("Doubled", verts, [(0, 1, 2, 3), (0, 1, 2, 3), (3, 2, 1, 0)], mat, bad["at"][::-1], s)
    if bad["nan"]:
        broken = add_shape("Broken", {"shape": "cube", "at": bad["at"][1:] + bad["at"][:1], "size": (0.5,) * 3,
                                      "rot": (0, 0, 0), "inward": False, "object_scale": False, "smooth": False},
                           mat, s)
        broken.data.vertices[0].co = (math.nan, 0.0, 0.0)


def add_light(name: str, lamp: dict, s: float) -> None:
    import bpy

    kind = lamp["type"]
    data = bpy.data.lights.new(name, kind)
    data.energy = 10.0 ** lamp["power"] * (1.0 if kind == "SUN" else s * s)
    data.color = lamp["color"]
    if kind in ("POINT", "SPOT"):
        data.shadow_soft_size = lamp["size"] * s
    if kind == "SPOT":
        data.spot_size, data.spot_blend = lamp["spot"], lamp["blend"]
    if kind == "AREA":
        data.shape = lamp["shape"]
        data.size, data.size_y = lamp["size"] * s, lamp["size_y"] * s
    if kind == "SUN":
        data.angle = lamp["angle"]
    link(name, data, lamp["at"], lamp["rot"], s)


def set_world(color) -> None:
    """No world at all (None), or a Background of `color`."""
    import bpy

    if color is None:
        bpy.context.scene.world = None
        return
    world = bpy.data.worlds.new("World")
    background = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    background.inputs["Color"].default_value = (*color, 1.0)
    background.inputs["Strength"].default_value = 1.0
    bpy.context.scene.world = world


def add_camera(c: dict, s: float) -> None:
    """A perspective or orthographic camera at `eye` looking at `target` (both × scale), clipping at 10⁻³ and
    10³ × scale."""
    import bpy
    from mathutils import Vector

    data = bpy.data.cameras.new("Camera")
    data.type = "ORTHO" if c["ortho"] else "PERSP"
    data.lens, data.ortho_scale = c["lens"], 4.0 * s
    data.clip_start, data.clip_end = 1e-3 * s, 1e3 * s
    eye = Vector(c["eye"]) * s
    look = Vector(c["target"]) * s - eye
    if look.length < 1e-3 * s:
        look = Vector((1.0, 0.0, 0.0))
    obj = link("Camera", data, c["eye"], look.to_track_quat("-Z", "Y").to_euler(), s)
    bpy.context.scene.camera = obj


def count_meshes() -> dict:
    """bpy's own count: loop triangles of each mesh object, and whether its world-space vertices are all finite."""
    import bpy

    depsgraph = bpy.context.evaluated_depsgraph_get()
    triangles, finite = {}, {}
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH":
            continue
        me = obj.evaluated_get(depsgraph).data
        me.calc_loop_triangles()
        triangles[obj.name] = len(me.loop_triangles)
        finite[obj.name] = all(math.isfinite(c) for v in me.vertices for c in obj.matrix_world @ v.co)
    return {"triangles": triangles, "finite": finite}


if __name__ == "__main__":
    serve()
