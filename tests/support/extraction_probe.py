# SPDX-License-Identifier: GPL-3.0-or-later
"""The bpy side of tests/blender/test_extraction.py, run there in ONE subprocess so Blender state never leaks into
the pytest process:
    python tests/support/extraction_probe.py OUT.json

It builds example scenes, extracts them with `extract_scene`, computes the same quantities independently through
bpy (evaluated meshes, object instances, light data) and writes a JSON summary. Each experiment is recorded
separately: one that raises stores its traceback, and only the tests that need it fail.
"""
import json
import os
import sys
import traceback

import bpy  # before bmesh/mathutils, which examples.scenes imports
import numpy as np
from mathutils import Vector

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

from examples import scenes  # noqa: E402

from bounce_gi.addon.extract import ExtractError, extract_scene  # noqa: E402


def _np(a):
    return np.asarray(a, np.float64).tolist()


def extract():
    return extract_scene(bpy.context.evaluated_depsgraph_get())


def update():
    bpy.context.view_layer.update()


def tris_of(scene, material_name):
    names = [m.name for m in scene.materials]
    return scene.material_index == names.index(material_name)


def blender_geometry():
    """Triangles and world bounds as Blender reports them, one evaluated mesh per visible instance."""
    dg = bpy.context.evaluated_depsgraph_get()
    total, per_object, points = 0, {}, []
    for inst in dg.object_instances:
        obj = inst.object
        if obj.type != "MESH" or not inst.show_self or obj.original.hide_render:
            continue
        me = obj.data
        n = len(me.loop_triangles)
        total += n
        per_object[obj.name] = per_object.get(obj.name, 0) + n
        co = np.empty(len(me.vertices) * 3, np.float64)
        me.vertices.foreach_get("co", co)
        m = np.array(inst.matrix_world, np.float64)
        points.append(co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3])
    pts = np.concatenate(points)
    return {"triangles": total, "per_object": per_object, "bounds": [_np(pts.min(0)), _np(pts.max(0))]}


def materials_of(scene):
    return {m.name: dict(base_color=_np(m.base_color), texture=m.base_color_texture, emission=_np(m.emission),
                         roughness=m.roughness, metallic=m.metallic, specular_layer=m.specular_layer)
            for m in scene.materials}


def extraction():
    scenes.build("extraction")
    sc = extract()
    lo, hi = sc.bounds()
    plane = bpy.data.objects["CustomNormals"]
    grey = tris_of(sc, "Grey")
    out = dict(triangles=sc.triangle_count, bounds=[_np(lo), _np(hi)], blender=blender_geometry(),
               statistics=sc.statistics(), warnings=sc.warnings,
               plane_normals=_np(sc.normals[grey]), plane_matrix=_np(np.array(plane.matrix_world)),
               custom_normal=list(scenes.CUSTOM_NORMAL))
    # Rotate and non-uniformly scale the plane: the normals must follow the inverse-transpose of its matrix.
    plane.rotation_euler = (0.4, -0.3, 1.1)
    plane.scale = (2.0, 0.5, 1.0)
    update()
    dg = bpy.context.evaluated_depsgraph_get()
    me = plane.evaluated_get(dg).data
    # Blender's own corner normals, in extraction order (loop triangles, corner by corner).
    blender_cn = np.array([[tuple(me.corner_normals[loop].vector) for loop in lt.loops]
                           for lt in me.loop_triangles], np.float64)
    sc = extract()
    grey = tris_of(sc, "Grey")
    out.update(moved_plane_normals=_np(sc.normals[grey]), moved_plane_positions=_np(sc.positions[grey]),
               moved_plane_matrix=_np(np.array(plane.matrix_world)), blender_corner_normals=_np(blender_cn))
    # Mirror it (negative X scale): the winding flips, extraction must keep it consistent with the normals.
    plane.rotation_euler = (0.0, 0.0, 0.0)
    plane.scale = (-1.0, 1.0, 1.0)
    update()
    sc = extract()
    grey = tris_of(sc, "Grey")
    out.update(mirrored_plane_normals=_np(sc.normals[grey]), mirrored_plane_positions=_np(sc.positions[grey]),
               mirrored_plane_matrix=_np(np.array(plane.matrix_world)))
    return out


def stage():
    scenes.build("light_sun")
    sphere, cube = bpy.data.objects["Sphere"], bpy.data.objects["Cube"]
    sc = extract()
    orange = tris_of(sc, "CubeOrange")
    out = dict(triangles=sc.triangle_count, blender=blender_geometry(),
               sphere_center=list(sphere.location), sphere_radius=0.6,
               sphere_tris=len(sphere.data.loop_triangles),
               positions=_np(sc.positions), normals=_np(sc.normals),
               cube_positions=_np(sc.positions[orange]), cube_normals=_np(sc.normals[orange]),
               cube_center=list(cube.location))
    # Mirror the cube (scale -1 on X).
    cube.scale = (-1.0, 1.0, 1.0)
    update()
    sc = extract()
    orange = tris_of(sc, "CubeOrange")
    out.update(mirrored_cube_positions=_np(sc.positions[orange]), mirrored_cube_normals=_np(sc.normals[orange]))
    cube.scale = (1.0, 1.0, 1.0)
    # hide_render: the sphere disappears from the extraction, the viewport visibility does not matter.
    sphere.hide_render = True
    update()
    sc = extract()
    out.update(hidden_triangles=sc.triangle_count, hidden_positions=_np(sc.positions),
               hidden_blender=blender_geometry())
    sphere.hide_render = False
    update()
    return out


def materials():
    scenes.build("light_sun")
    sphere, cube = bpy.data.objects["Sphere"], bpy.data.objects["Cube"]
    principled = bpy.data.materials.new("PrincipledTest")  # a new material is a Principled BSDF tree
    bsdf = next(n for n in principled.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (0.2, 0.4, 0.6, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.35
    bsdf.inputs["Metallic"].default_value = 0.1
    sphere.data.materials[0] = principled
    glass = bpy.data.materials.new("GlassTest")
    nt = glass.node_tree
    nt.nodes.clear()
    out_node = nt.nodes.new("ShaderNodeOutputMaterial")
    g = nt.nodes.new("ShaderNodeBsdfGlass")
    nt.links.new(g.outputs["BSDF"], out_node.inputs["Surface"])
    glass.diffuse_color = (0.9, 0.1, 0.05, 1.0)
    cube.data.materials[0] = glass
    update()
    sc = extract()
    return dict(materials=materials_of(sc), warnings=sc.warnings,
                used=sorted({sc.materials[i].name for i in np.unique(sc.material_index)}),
                glass_viewport=list(glass.diffuse_color[:3]))


def no_camera():
    scenes.build("light_sun")
    bpy.context.scene.camera = None
    try:
        extract()
    except ExtractError as exc:
        return dict(raised="ExtractError", message=str(exc))
    except Exception as exc:  # the wrong exception type
        return dict(raised=type(exc).__name__, message=str(exc))
    return dict(raised=None, message="")


def textured():
    scenes.build("textured")
    sc = extract()
    floor = tris_of(sc, "Checker")
    return dict(materials=materials_of(sc), floor_uvs=_np(sc.uvs[floor]),
                textures=[dict(name=t.name, shape=list(t.pixels.shape), dtype=str(t.pixels.dtype),
                               colors=_np(np.unique(t.pixels.reshape(-1, 4)[:, :3].round(6), axis=0)),
                               interpolation=t.interpolation, extension=t.extension) for t in sc.textures],
                image_size=list(bpy.data.images["Checker"].size))


def light_record_bpy(ob):
    ld = ob.data
    rec = dict(type=ld.type, energy=ld.energy, color=list(ld.color), matrix=_np(np.array(ob.matrix_world)),
               direction=list((ob.matrix_world.to_3x3() @ Vector((0, 0, -1))).normalized()))
    if ld.type in ("POINT", "SPOT"):
        rec["radius"] = ld.shadow_soft_size
    if ld.type == "SPOT":
        rec.update(spot_size=ld.spot_size, spot_blend=ld.spot_blend)
    if ld.type == "SUN":
        rec["angle"] = ld.angle
    if ld.type == "AREA":
        rec.update(shape=ld.shape, size=ld.size, size_y=ld.size_y)
    return rec


def light_record_ours(light):
    return dict(type=light.type, power=light.power, color=_np(light.color), matrix=_np(light.matrix_world),
                direction=_np(light.direction), radius=light.radius, spot_size=light.spot_size,
                spot_blend=light.spot_blend, angle=light.angle, shape=light.shape, size=light.size,
                size_y=light.size_y)


def lights():
    out = {}
    for name in scenes.SCENES:
        if not name.startswith("light_"):
            continue
        scenes.build(name)
        sc = extract()
        out[name] = dict(bpy={ob.name: light_record_bpy(ob) for ob in bpy.data.objects if ob.type == "LIGHT"},
                         ours={lt.name: light_record_ours(lt) for lt in sc.lights})
    return out


def light_settings():
    scenes.build("light_point")
    ob = bpy.data.objects["PointLight"]
    ld = ob.data

    def point():
        (lt,) = extract().lights
        return dict(power=lt.power, color=_np(lt.color))

    base = point()
    ld.exposure = 1.0
    update()
    exposed = point()
    ld.exposure = 0.0
    ld.color = (1.0, 0.8, 0.6)
    ld.use_temperature = True
    ld.temperature = 3000.0
    update()
    warm = point()
    return dict(energy=ld.energy, base=base, exposed=exposed, warm=warm, color=list(ld.color),
                temperature_color=list(ld.temperature_color))


EXPERIMENTS = (extraction, stage, materials, no_camera, textured, lights, light_settings)


def main(out_path):
    result = {}
    for fn in EXPERIMENTS:
        try:
            result[fn.__name__] = fn()
        except Exception:
            result[fn.__name__] = {"error": traceback.format_exc()}
    with open(out_path, "w") as f:
        json.dump(result, f)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(f"usage: {sys.argv[0]} OUT.json (normally run by tests/blender/test_extraction.py)")
    main(sys.argv[1])
