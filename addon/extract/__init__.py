"""Blender → `gpu_kernels.scene.Scene`: the only place that reads scene data through bpy.

Meshes come from the evaluated depsgraph (modifiers applied, collection and geometry-node instances included via
`depsgraph.object_instances`), copied with `foreach_get` into numpy — no per-vertex Python loops.
"""
from __future__ import annotations

import math

import numpy as np

from ...gpu_kernels.scene import Camera, Light, Material, Scene, Texture, World
from . import materials as mat_reader

GEOMETRY_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META", "CURVES"}


class ExtractError(ValueError):
    """The Blender scene cannot be turned into a renderable Scene; the message is for the user."""


def _mesh_arrays(mesh) -> dict:
    """Local-space corner arrays of an evaluated mesh: positions, normals, uvs, material index per triangle."""
    mesh.calc_loop_triangles()
    nt = len(mesh.loop_triangles)
    if nt == 0:
        return None
    tri_loops = np.empty(nt * 3, np.int32)
    mesh.loop_triangles.foreach_get("loops", tri_loops)
    tri_mat = np.empty(nt, np.int32)
    mesh.loop_triangles.foreach_get("material_index", tri_mat)
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    loop_vert = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vert)
    # corner_normals (Blender 4.1+) are the normals Blender shades with: smooth, flat, sharp edges, custom.
    cn = np.empty(len(mesh.loops) * 3, np.float32)
    mesh.corner_normals.foreach_get("vector", cn)
    uv_layer = next((l for l in mesh.uv_layers if l.active_render), None) or mesh.uv_layers.active
    if uv_layer is not None:
        uv = np.empty(len(mesh.loops) * 2, np.float32)
        uv_layer.uv.foreach_get("vector", uv)
        uv = uv.reshape(-1, 2)[tri_loops].reshape(nt, 3, 2)
    else:
        uv = np.zeros((nt, 3, 2), np.float32)
    return {
        "positions": co.reshape(-1, 3)[loop_vert[tri_loops]].reshape(nt, 3, 3),
        "normals": cn.reshape(-1, 3)[tri_loops].reshape(nt, 3, 3),
        "uvs": uv,
        "material_index": tri_mat,
    }


def _transform(arrays: dict, matrix: np.ndarray) -> tuple:
    m = np.asarray(matrix, np.float64)
    pos = arrays["positions"].astype(np.float64) @ m[:3, :3].T + m[:3, 3]
    normal_matrix = np.linalg.inv(m[:3, :3]).T
    nrm = arrays["normals"].astype(np.float64) @ normal_matrix.T
    nrm /= np.maximum(np.linalg.norm(nrm, axis=-1, keepdims=True), 1e-30)
    uvs = arrays["uvs"]
    if np.linalg.det(m[:3, :3]) < 0:
        # A mirroring transform reverses the winding; swap two corners so the geometric normal (from the
        # winding) agrees with the shading normals again.
        pos, nrm, uvs = pos[:, ::-1], nrm[:, ::-1], uvs[:, ::-1]
    return pos.astype(np.float32), nrm.astype(np.float32), np.ascontiguousarray(uvs)


def _light(obj, matrix) -> tuple[Light, list]:
    data = obj.data
    warnings = []
    color = np.array(data.color[:3], np.float64)
    if getattr(data, "use_temperature", False):
        color = color * np.array(data.temperature_color[:3])
    power = float(data.energy) * 2.0 ** float(getattr(data, "exposure", 0.0))
    if getattr(data, "use_nodes", False) and data.node_tree is not None:
        scale, warn = mat_reader.light_node_scale(data.node_tree)
        color = color * scale
        if warn:
            warnings.append(f"light '{obj.name}': {warn}")
    light = Light(name=obj.name, type=data.type, color=tuple(color), power=power,
                  matrix_world=np.array(matrix, np.float64), cast_shadow=bool(getattr(data, "use_shadow", True)))
    if data.type in ("POINT", "SPOT"):
        light.radius = float(data.shadow_soft_size)
        light.soft_falloff = bool(getattr(data, "use_soft_falloff", True))
        if not getattr(data, "normalize", True):
            # Cycles (scene/light.cpp): without normalisation the emitter radiance is P/π instead of P/(π·area),
            # area = 4πr² (or 4 for r = 0), so the intensity P/(4π) grows by that area.
            light.power *= 4.0 * math.pi * light.radius ** 2 if light.radius > 0 else 4.0
    if data.type == "SPOT":
        light.spot_size = float(data.spot_size)
        light.spot_blend = float(data.spot_blend)
    if data.type == "SUN":
        light.angle = float(data.angle)
    if data.type == "AREA":
        light.shape, light.size, light.size_y = data.shape, float(data.size), float(data.size_y)
        if getattr(data, "spread", math.pi) < math.pi - 1e-4:
            warnings.append(f"area light '{obj.name}' has spread < 180°; it is lit as a full-spread light")
        if not getattr(data, "normalize", True):
            # Without normalisation, Cycles does not divide the power by the area: radiance = P/π per m².
            m = np.asarray(matrix, np.float64)
            sx, sy = np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])
            side_y = light.size if light.shape in ("SQUARE", "DISK") else light.size_y
            area = light.size * side_y * sx * sy * (math.pi / 4 if light.shape in ("DISK", "ELLIPSE") else 1.0)
            light.power *= area
    return light, warnings


def _camera(scene) -> Camera:
    cam_obj = scene.camera
    if cam_obj is None:
        raise ExtractError("the scene has no camera")
    data = cam_obj.data
    if data.type not in ("PERSP", "ORTHO"):
        raise ExtractError(f"camera '{cam_obj.name}' is {data.type}; only perspective and orthographic are supported")
    m = np.array(cam_obj.matrix_world, np.float64)
    for i in range(3):  # the camera's scale does not change Blender's projection
        m[:3, i] /= np.linalg.norm(m[:3, i])
    return Camera(matrix_world=m, type=data.type, lens=float(data.lens), sensor_width=float(data.sensor_width),
                  sensor_height=float(data.sensor_height), sensor_fit=data.sensor_fit,
                  ortho_scale=float(data.ortho_scale), shift_x=float(data.shift_x), shift_y=float(data.shift_y),
                  clip_start=float(data.clip_start), clip_end=float(data.clip_end))


def _world(scene, warnings) -> World:
    world = scene.world
    if world is None:
        return World((0.0, 0.0, 0.0))
    color, warn = mat_reader.world_color(world)
    if warn:
        warnings.append(warn)
    return World(tuple(color))


def extract_scene(depsgraph, resolution=None) -> Scene:
    """Build a Scene from an evaluated depsgraph. `resolution` overrides the scene's render size (W, H)."""
    scene = depsgraph.scene_eval
    warnings: list[str] = []
    materials: list[Material] = [Material("Default", (0.8, 0.8, 0.8))]
    textures: list[Texture] = []
    material_ids: dict = {}  # original material name -> index in `materials`
    image_ids: dict = {}
    mesh_cache: dict = {}
    chunks = {"positions": [], "normals": [], "uvs": [], "material_index": []}
    lights: list[Light] = []

    def material_index(material) -> int:
        if material is None:
            return 0
        key = material.original.name if hasattr(material, "original") else material.name
        if key not in material_ids:
            mat, warn = mat_reader.read_material(material, textures, image_ids)
            if warn:
                warnings.append(warn)
            material_ids[key] = len(materials)
            materials.append(mat)
        return material_ids[key]

    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.original.hide_render:
            continue
        matrix = np.array(inst.matrix_world, np.float64)
        if obj.type == "LIGHT":
            light, warns = _light(obj, matrix)
            lights.append(light)
            warnings.extend(warns)
            continue
        if obj.type not in GEOMETRY_TYPES or not inst.show_self:
            continue
        mesh_key = (obj.name, obj.data.name if obj.data is not None else "")
        if mesh_key not in mesh_cache:
            mesh = obj.data if obj.type == "MESH" else obj.to_mesh()
            arrays = _mesh_arrays(mesh) if mesh is not None else None
            slots = [material_index(slot.material) for slot in obj.material_slots] or [0]
            if arrays is not None:
                idx = np.clip(arrays["material_index"], 0, len(slots) - 1)
                arrays["material_index"] = np.asarray(slots, np.int32)[idx]
            if obj.type != "MESH":
                obj.to_mesh_clear()
            mesh_cache[mesh_key] = arrays
        arrays = mesh_cache[mesh_key]
        if arrays is None:
            continue
        pos, nrm, uvs = _transform(arrays, matrix)
        chunks["positions"].append(pos)
        chunks["normals"].append(nrm)
        chunks["uvs"].append(uvs)
        chunks["material_index"].append(arrays["material_index"])

    def cat(name, shape, dtype):
        return np.concatenate(chunks[name]).astype(dtype) if chunks[name] else np.zeros(shape, dtype)

    render = scene.render
    if resolution is None:
        pct = render.resolution_percentage / 100.0
        resolution = (max(1, int(render.resolution_x * pct)), max(1, int(render.resolution_y * pct)))
    return Scene(
        positions=cat("positions", (0, 3, 3), np.float32), normals=cat("normals", (0, 3, 3), np.float32),
        uvs=cat("uvs", (0, 3, 2), np.float32), material_index=cat("material_index", (0,), np.int32),
        materials=materials, textures=textures, lights=lights, world=_world(scene, warnings),
        camera=_camera(scene), resolution=tuple(int(v) for v in resolution),
        pixel_aspect=(float(render.pixel_aspect_x), float(render.pixel_aspect_y)), warnings=warnings)
