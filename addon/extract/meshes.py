# SPDX-License-Identifier: GPL-3.0-or-later
"""Geometry: evaluated meshes of the visible object instances → world-space triangle arrays.

Meshes come from the evaluated depsgraph (modifiers applied, collection and geometry-node instances included via
`depsgraph.object_instances`), copied with `foreach_get` into numpy — no per-vertex Python loops. A mesh shared by
several instances is read once and transformed per instance.
"""
from __future__ import annotations

import numpy as np

from ...gpu_kernels.scene import finite_normals

GEOMETRY_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META", "CURVES"}
ARRAYS = {"positions": ((0, 3, 3), np.float32), "normals": ((0, 3, 3), np.float32), "uvs": ((0, 3, 2), np.float32),
          "material_index": ((0,), np.int32)}  # name -> (shape when empty, dtype) of the Scene's triangle arrays


def mesh_arrays(mesh) -> dict | None:
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


def transform(arrays: dict, matrix: np.ndarray) -> tuple:
    """World-space (positions, normals, uvs) of local corner arrays under an instance's matrix."""
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


def object_arrays(obj, material_index) -> dict | None:
    """An evaluated object's local corner arrays, its material slots mapped to scene material indices through
    `material_index(bpy material or None) -> int`; None when it has no triangles."""
    mesh = obj.data if obj.type == "MESH" else obj.to_mesh()
    arrays = mesh_arrays(mesh) if mesh is not None else None
    slots = [material_index(slot.material) for slot in obj.material_slots] or [0]
    if arrays is not None:
        idx = np.clip(arrays["material_index"], 0, len(slots) - 1)
        arrays["material_index"] = np.asarray(slots, np.int32)[idx]
    if obj.type != "MESH":
        obj.to_mesh_clear()
    return arrays


class Geometry:
    """The world-space triangles of every instance added, in instance order. An instance with a NaN or infinite
    vertex position (after its transform) is left out with a warning naming it: one broken object must not cost the
    user the whole render."""

    def __init__(self, material_index, warnings: list):
        self.material_index = material_index  # bpy material or None -> index in the Scene's materials
        self.warnings = warnings
        self.chunks = {name: [] for name in ARRAYS}
        self.mesh_cache: dict = {}  # (object name, mesh name) -> local arrays, or None without triangles
        self.skipped: set = set()  # objects already warned about

    def add_instance(self, obj, matrix: np.ndarray) -> None:
        mesh_key = (obj.name, obj.data.name if obj.data is not None else "")
        if mesh_key not in self.mesh_cache:
            self.mesh_cache[mesh_key] = object_arrays(obj, self.material_index)
        arrays = self.mesh_cache[mesh_key]
        if arrays is None:
            return
        pos, nrm, uvs = transform(arrays, matrix)
        if not np.isfinite(pos).all():
            if obj.name not in self.skipped:
                self.skipped.add(obj.name)
                bad = int((~np.isfinite(pos).all(axis=-1)).any(axis=-1).sum())
                self.warnings.append(f"object '{obj.name}' has {bad} triangle(s) with a NaN or infinite vertex "
                                     "position and is left out")
            return
        self.chunks["positions"].append(pos)
        self.chunks["normals"].append(finite_normals(pos, nrm))
        self.chunks["uvs"].append(uvs)
        self.chunks["material_index"].append(arrays["material_index"])

    def arrays(self) -> dict:
        """{positions, normals, uvs, material_index}: the Scene's triangle arrays (empty ones without triangles)."""
        return {name: np.concatenate(self.chunks[name]).astype(dtype) if self.chunks[name] else np.zeros(shape, dtype)
                for name, (shape, dtype) in ARRAYS.items()}
