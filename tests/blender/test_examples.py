# SPDX-License-Identifier: GPL-3.0-or-later
"""The example scenes (examples/scenes/): every scene builds, has one camera, light,
the expected objects and settings; one .blend round-trips; Cycles lights `cornell`
(test_user_scenes.py checks the scenes like users' from the same summary).

bpy work runs in ONE subprocess (this file run as a script with --collect), so Blender
state never leaks into the pytest process; it writes a JSON summary that the tests read.
"""
import json
import math
import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# name -> (mesh objects, lights, empties, emissive materials) in bpy.data
EXPECTED_COUNTS = {
    "cornell": (7, 1, 0, 0),
    "cornell_emissive": (8, 0, 0, 1),
    "light_sun": (4, 1, 0, 0),
    "light_point": (4, 1, 0, 0),
    "light_point_soft": (4, 1, 0, 0),
    "light_spot": (4, 1, 0, 0),
    "light_area_square": (4, 1, 0, 0),
    "light_area_disk": (4, 1, 0, 0),
    "light_mixed": (4, 4, 0, 0),
    "textured": (4, 1, 0, 0),
    "principled": (4, 1, 0, 0),
    "camera_shift": (4, 1, 0, 0),
    "camera_ortho": (4, 1, 0, 0),
    "extraction": (5, 1, 3, 0),
    "spot_room": (7, 1, 0, 0),
    "courtyard": (6, 1, 0, 0),
    "cornell_animated": (7, 1, 0, 0),
    "default_principled": (11, 1, 0, 0),
    "metals": (7, 2, 0, 0),
    "window_room": (12, 1, 0, 0),
    "rug_room": (9, 1, 0, 0),
    "thin_walls": (17, 1, 0, 0),
    "lamp_room": (15, 0, 0, 1),
    "many_lights": (7, 20, 0, 0),
    "outdoor": (23, 1, 0, 0),
    "product_shot": (5, 2, 0, 0),
    "furnished": (41, 2, 0, 1),
}
SKY_LIT = {"window_room", "thin_walls", "outdoor", "furnished"}  # world strength 1, a constant colour
COLOURED_LIGHTS = {"many_lights"}  # warm and cool white point lights


# --------------------------------------------------------------------------- subprocess side


def _lights(bpy, objs):
    """Light data per light object: type, energy, colour, placement and the type's own settings."""
    from mathutils import Vector

    lights = {}
    for ob in objs:
        if ob.type != "LIGHT":
            continue
        ld = ob.data
        d = ob.matrix_world.to_3x3() @ Vector((0.0, 0.0, -1.0))
        info = dict(type=ld.type, energy=ld.energy, color=tuple(ld.color), location=tuple(ob.location),
                    direction=tuple(d.normalized()), radius=ld.shadow_soft_size)
        if ld.type == "SUN":
            info["angle"] = ld.angle
        if ld.type == "SPOT":
            info.update(spot_size=ld.spot_size, spot_blend=ld.spot_blend)
        if ld.type == "AREA":
            info.update(shape=ld.shape, size=ld.size)
        lights[ob.name] = info
    return lights


PRINCIPLED_INPUTS = ("Base Color", "Roughness", "Metallic", "IOR", "Specular IOR Level", "Emission Strength")


def _materials(bpy):
    """(names of emissive materials, node types per material, Principled BSDF inputs per material)."""
    emissive = []
    node_types, principled = {}, {}
    for mat in bpy.data.materials:
        types = sorted({n.bl_idname for n in mat.node_tree.nodes})
        node_types[mat.name] = types
        for n in mat.node_tree.nodes:
            if n.bl_idname == "ShaderNodeEmission" and n.inputs["Strength"].default_value > 0:
                emissive.append(mat.name)
            if n.bl_idname == "ShaderNodeBsdfPrincipled":
                v = {k: n.inputs[k].default_value for k in PRINCIPLED_INPUTS}
                principled[mat.name] = {k: list(x)[:3] if hasattr(x, "__len__") else x for k, x in v.items()}
                if v["Emission Strength"] > 0:
                    emissive.append(mat.name)
    return emissive, node_types, principled


def _meshes(objs):
    """World-space bounding box, triangle count and closedness (every edge between two faces) per mesh object."""
    import numpy as np

    out = {}
    for ob in objs:
        if ob.type != "MESH":
            continue
        me = ob.data
        pts = np.array([tuple(ob.matrix_world @ v.co) for v in me.vertices])
        edge_faces = {}
        for p in me.polygons:
            for key in p.edge_keys:
                edge_faces[key] = edge_faces.get(key, 0) + 1
        out[ob.name] = dict(min=pts.min(0).tolist(), max=pts.max(0).tolist(),
                            triangles=sum(len(p.vertices) - 2 for p in me.polygons),
                            closed=all(n == 2 for n in edge_faces.values()),
                            material=me.materials[0].name if me.materials else None)
    return out


def _camera(scene):
    from mathutils import Vector

    cam_ob = scene.camera
    cam = cam_ob.data
    m = cam_ob.matrix_world.to_3x3()
    return dict(name=cam_ob.name, type=cam.type, lens=cam.lens, sensor_fit=cam.sensor_fit,
                shift=(cam.shift_x, cam.shift_y), ortho_scale=cam.ortho_scale,
                location=tuple(cam_ob.location), view=tuple(m @ Vector((0, 0, -1))),
                right=tuple(m @ Vector((1, 0, 0))), up=tuple(m @ Vector((0, 1, 0))))


def _extraction(bpy, objs):
    """What the `extraction` scene sets up: modifiers, the excluded collection and its instances, custom normals."""
    blob = bpy.data.objects["Blob"]
    dg = bpy.context.evaluated_depsgraph_get()
    me = bpy.data.objects["CustomNormals"].data
    return dict(
        modifiers=[(md.type, getattr(md, "levels", None), getattr(md, "render_levels", None))
                   for md in blob.modifiers],
        props_excluded=bpy.context.view_layer.layer_collection.children["Props"].exclude,
        props_objects=sorted(o.name for o in bpy.data.collections["Props"].objects),
        empties=[(o.instance_type, o.instance_collection.name if o.instance_collection else None)
                 for o in objs if o.type == "EMPTY"],
        instances=sorted(i.object.name for i in dg.object_instances if i.is_instance),
        has_custom_normals=me.has_custom_normals,
        corner_normals=[tuple(c.vector) for c in me.corner_normals],
    )


def _summarize(bpy, name):
    """Plain-data description of the current scene."""
    scene = bpy.context.scene
    objs = list(bpy.data.objects)
    lights = _lights(bpy, objs)
    emissive, node_types, principled = _materials(bpy)
    # Polygon normals of named quads (world space), to check walls face inward.
    normals = {}
    for ob in objs:
        if ob.type == "MESH" and len(ob.data.polygons) <= 4 and not ob.modifiers:
            n = ob.matrix_world.to_3x3() @ ob.data.polygons[0].normal
            normals[ob.name] = tuple(round(c, 4) for c in n)
    world_bg = scene.world.node_tree.nodes["Background"] if scene.world else None
    out = dict(
        objects={ob.name: ob.type for ob in objs},
        n_cameras=sum(ob.type == "CAMERA" for ob in objs),
        camera=_camera(scene),
        resolution=(scene.render.resolution_x, scene.render.resolution_y,
                    scene.render.resolution_percentage),
        world_strength=world_bg.inputs["Strength"].default_value if world_bg else None,
        world_color_linked=world_bg.inputs["Color"].is_linked if world_bg else None,
        principled=principled,
        meshes=_meshes(objs),
        lights=lights,
        emissive=emissive,
        node_types=node_types,
        normals=normals,
        images={im.name: dict(packed=im.packed_file is not None, float=im.is_float,
                              colorspace=im.colorspace_settings.name, size=tuple(im.size))
                for im in bpy.data.images},
    )
    if name == "extraction":
        out["extraction"] = _extraction(bpy, objs)
    return out


def _collect(out_path, tmpdir):
    import bpy  # noqa: F401  (before bmesh, inside examples.scenes)
    import numpy as np

    sys.path.insert(0, ROOT)
    from examples import scenes

    result = {"scenes": {}}
    for name in scenes.SCENES:
        scenes.build(name)
        result["scenes"][name] = _summarize(bpy, name)

    # Round trip: the saved textured scene still carries its packed image.
    path = scenes.save("textured", os.path.join(tmpdir, "textured.blend"))
    bpy.ops.wm.open_mainfile(filepath=path)
    img = bpy.data.images["Checker"]
    px = np.empty(len(img.pixels), np.float32)
    img.pixels.foreach_get(px)
    result["reloaded_image"] = dict(packed=img.packed_file is not None,
                                    colors=sorted({tuple(float(c) for c in np.round(p, 4)) for p in px.reshape(-1, 4)[:, :3]}))

    # Tiny Cycles render of the Cornell box.
    scenes.build("cornell")
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = 16
    sc.cycles.use_adaptive_sampling = False
    sc.cycles.use_denoising = False
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.filepath = os.path.join(tmpdir, "cornell.exr")
    bpy.ops.render.render(write_still=True)
    im = bpy.data.images.load(sc.render.filepath)
    px = np.empty(len(im.pixels), np.float32)
    im.pixels.foreach_get(px)
    rgb = px.reshape(24, 32, 4)[..., :3]
    result["cornell_render"] = dict(mean=float(rgb.mean()), mean_rgb=rgb.reshape(-1, 3).mean(0).tolist(),
                                    finite=bool(np.isfinite(rgb).all()))
    with open(out_path, "w") as f:
        json.dump(result, f)


# --------------------------------------------------------------------------- pytest side


@pytest.fixture(scope="module")
def data(examples_summary):
    """What _collect wrote (tests/blender/conftest.py runs this file with --collect once a session)."""
    return examples_summary


def close(a, b, tol=1e-4):
    return all(abs(x - y) <= tol for x, y in zip(a, b, strict=True))


def test_all_scenes_build(data):
    assert sorted(data["scenes"]) == sorted(EXPECTED_COUNTS)


@pytest.mark.parametrize("name", sorted(EXPECTED_COUNTS))
def test_scene_basics(data, name):
    s = data["scenes"][name]
    assert s["n_cameras"] == 1 and s["camera"]["name"] in s["objects"]
    assert s["resolution"] == [160, 120, 100]
    assert s["world_strength"] == (1.0 if name in SKY_LIT else 0.0)
    assert s["lights"] or s["emissive"], "scene has no light source"
    types = list(s["objects"].values())
    counts = (types.count("MESH"), types.count("LIGHT"), types.count("EMPTY"), len(s["emissive"]))
    assert counts == EXPECTED_COUNTS[name]
    for mat, nodes in s["node_types"].items():
        assert "ShaderNodeOutputMaterial" in nodes, mat
        assert {"ShaderNodeBsdfDiffuse", "ShaderNodeBsdfPrincipled", "ShaderNodeEmission"} & set(nodes), (mat, nodes)
    for light in s["lights"].values():
        assert light["color"] == [1.0, 1.0, 1.0] or name in COLOURED_LIGHTS


def test_cornell(data):
    s = data["scenes"]["cornell"]
    (light,) = s["lights"].values()
    assert light["type"] == "AREA" and light["shape"] == "SQUARE"
    assert light["energy"] == pytest.approx(60.0)
    assert light["size"] == pytest.approx(0.5)
    assert close(light["location"], (0, 0, 1.98))
    assert close(light["direction"], (0, 0, -1))
    n = s["normals"]  # single-sided walls face into the box
    assert close(n["Floor"], (0, 0, 1)) and close(n["Ceiling"], (0, 0, -1))
    assert close(n["BackWall"], (0, -1, 0))
    assert close(n["LeftWall"], (1, 0, 0)) and close(n["RightWall"], (-1, 0, 0))
    cam = s["camera"]
    assert close(cam["location"], (0, -3.9, 1)) and close(cam["view"], (0, 1, 0))
    assert cam["lens"] == pytest.approx(38.0)


def test_cornell_emissive(data):
    s = data["scenes"]["cornell_emissive"]
    assert not s["lights"] and s["emissive"] == ["Emitter"]
    assert close(s["normals"]["LightPanel"], (0, 0, -1))
    assert set(s["objects"]) == set(data["scenes"]["cornell"]["objects"]) - {"AreaLight"} | {"LightPanel"}


def test_stage_lights(data):
    sc = data["scenes"]
    sun = sc["light_sun"]["lights"]["Sun"]
    assert sun["type"] == "SUN" and sun["energy"] == pytest.approx(3.0)
    assert sun["angle"] == pytest.approx(math.radians(0.5))
    assert sun["direction"][0] > 0 and sun["direction"][2] < 0  # from the upper left
    for name, radius in (("light_point", 0.0), ("light_point_soft", 0.25)):
        p = sc[name]["lights"]["PointLight"]
        assert p["energy"] == pytest.approx(500.0) and p["radius"] == pytest.approx(radius)
        assert close(p["location"], (1.5, -1.5, 3))
    spot = sc["light_spot"]["lights"]["SpotLight"]
    assert spot["energy"] == pytest.approx(800.0) and spot["radius"] == 0.0
    assert spot["spot_size"] == pytest.approx(math.radians(60)) and spot["spot_blend"] == pytest.approx(0.3)
    to_cube = [c - l for c, l in zip((-1, 0, 0.5), spot["location"], strict=True)]
    norm = math.sqrt(sum(c * c for c in to_cube))
    assert close(spot["direction"], [c / norm for c in to_cube])
    sq = sc["light_area_square"]["lights"]["AreaLight"]
    assert (sq["shape"], sq["size"], sq["energy"]) == ("SQUARE", 1.0, 300.0)
    assert sq["direction"][1] > 0 and sq["direction"][2] == pytest.approx(-math.cos(math.radians(20)), abs=1e-5)
    disk = sc["light_area_disk"]["lights"]["AreaLight"]
    assert disk["shape"] == "DISK" and disk["size"] == pytest.approx(1.2) and disk["energy"] == 300.0
    mixed = {v["type"]: v["energy"] for v in sc["light_mixed"]["lights"].values()}
    assert mixed == {"SUN": 1.0, "POINT": 200.0, "SPOT": 400.0, "AREA": 150.0}
    for name in ("light_sun", "light_point", "light_mixed", "textured"):
        cam = sc[name]["camera"]
        assert close(cam["location"], (0, -7, 3.2)) and cam["lens"] == 35.0


def test_textured_image(data):
    s = data["scenes"]["textured"]
    assert s["images"]["Checker"] == dict(packed=True, float=True, colorspace="Linear Rec.709", size=[64, 64])
    assert "ShaderNodeTexImage" in s["node_types"]["Checker"]
    reloaded = data["reloaded_image"]
    assert reloaded["packed"]
    assert len(reloaded["colors"]) == 2  # exact linear values, no colourspace conversion
    assert reloaded["colors"][0] == pytest.approx([0.1, 0.3, 0.7], abs=1e-6)
    assert reloaded["colors"][1] == pytest.approx([0.8, 0.8, 0.8], abs=1e-6)


def test_cameras(data):
    cam = data["scenes"]["camera_shift"]["camera"]
    assert cam["sensor_fit"] == "VERTICAL" and close(cam["shift"], (0.1, -0.05))
    roll = math.degrees(math.atan2(abs(cam["right"][2]), cam["up"][2]))  # about the view axis
    assert roll == pytest.approx(15.0, abs=0.01)
    cam = data["scenes"]["camera_ortho"]["camera"]
    assert cam["type"] == "ORTHO" and cam["ortho_scale"] == 8.0
    assert math.degrees(math.asin(-cam["view"][2])) == pytest.approx(45.0, abs=0.01)


def test_extraction(data):
    e = data["scenes"]["extraction"]["extraction"]
    assert e["modifiers"] == [["MIRROR", None, None], ["SUBSURF", 2, 2]]
    assert e["props_excluded"] and e["props_objects"] == ["Cone", "Cylinder"]
    assert e["empties"] == [["COLLECTION", "Props"]] * 3
    assert e["instances"] == ["Cone"] * 3 + ["Cylinder"] * 3
    assert e["has_custom_normals"]
    for n in e["corner_normals"]:
        assert close(n, (math.sqrt(0.5), 0, math.sqrt(0.5)), tol=1e-3)


def test_gi_rooms(data):
    room = data["scenes"]["spot_room"]
    (spot,) = room["lights"].values()
    assert spot["type"] == "SPOT" and spot["energy"] == 600.0
    assert spot["spot_size"] == pytest.approx(math.radians(70)) and close(spot["direction"], (0, 0, -1))
    cam = room["camera"]["location"]
    assert -2 < cam[0] < 2 and -2 < cam[1] < 2 and 0 < cam[2] < 2.6
    yard = data["scenes"]["courtyard"]
    assert yard["lights"]["Sun"]["energy"] == 5.0
    cam = yard["camera"]["location"]
    assert -3 < cam[0] < 3 and -3 < cam[1] < 3 and 0 < cam[2] < 3


def test_cornell_renders_lit(data):
    r = data["cornell_render"]
    assert r["finite"]
    assert r["mean"] > 0.02, r
    red, green, _ = r["mean_rgb"]
    assert red > green * 0.8  # red wall and warm white walls show up


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--collect":
        _collect(sys.argv[2], sys.argv[3])
    else:
        sys.exit(f"usage: {sys.argv[0]} --collect OUT.json TMPDIR (normally run by pytest)")
