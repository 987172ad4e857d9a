# SPDX-License-Identifier: GPL-3.0-or-later
"""The steps of "Bake GI to Color Attribute" (`bounce_gi.bake_color_attribute`, bake_operator.py) as plain functions.

Every visible mesh (or the selected ones) gets a FLOAT_COLOR, POINT-domain attribute "BounceGI" holding, per vertex,
the indirect diffuse light without albedo — irradiance / π, what Cycles bakes with type DIFFUSE, pass filter
INDIRECT, colour off, into a point attribute — optionally plus the direct light, optionally times the diffuse colour.

How a vertex is evaluated. Cycles bakes a point attribute at every face corner, exactly at the vertex, and averages
the corners of each vertex. A voxel method cannot resolve light closer to a surface than about one cell: at a room's
corner the cell that holds the vertex also holds the neighbouring wall. VCT's cones from there see into that wall,
so its corners are evaluated 1.0 cell in; the LPV's receivers keep each wall's surfaces apart within a voxel
(lpv/receivers.py), so its corners need only a little (0.3 cells: best on spot_room, within 0.005 of the best on
the Cornell box and 0.02 on the courtyard). Each corner is evaluated at the vertex moved INSET_CELLS cells of the
method's grid toward its face's centre (at most INSET_LIMIT of the way there, so a small face keeps its sample
inside), with the corner's normal, and the corners are averaged per vertex, as Cycles does. Method "none" has no
grid and is evaluated at the vertices. The measured errors are in the README.

start_bake() collects the corners (foreach_get into numpy, no per-vertex Python loops) and extracts the scene on the
main thread, then submits one GPU job for every corner of every mesh (Engine.submit_points); finish_bake() writes the
attributes (foreach_set) once the job is done, so a failed or cancelled bake writes nothing. Meshes whose modifiers
change the vertex count cannot take per-vertex values on their original data: they are left out with a warning.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from .preview import PreviewError, one_line, render_settings_of, wait_result

ATTRIBUTE = "BounceGI"
# How far a corner's sample moves toward its face's centre, in cells of the method's grid (chosen on cornell,
# spot_room, courtyard: the docstring; README).
INSET_CELLS = {"lpv": 0.3, "vct": 1.0}
INSET_LIMIT = 0.45  # ... but at most this fraction of the way to the centre
EXTRACT_SIZE = (64, 64)  # the bake renders no image; extraction wants a size
# The LPV's first bounce is its RSM's texels binned into the cached transport's clusters (lpv/clusters.bin_flux): a
# cluster's flux is right only to within the texels along its edges, and an area light's views get few texels each
# (lpv/rsm.view_resolution; with 2048 clusters a strip of the Cornell box's floor along a wall got 1.4x the flux per
# area of the strip next to it). The image averages that out over many clusters; a vertex at a junction reads the
# clusters right beside it. A bake runs once, so it renders the RSM this many times finer than a render (measured:
# README).
BAKE_RSM_SCALE = 2


@dataclass
class BakeTarget:
    """One mesh's face corners in world space."""
    obj: object
    positions: np.ndarray  # (L, 3) the corners' vertices
    centres: np.ndarray  # (L, 3) the centre of each corner's face
    normals: np.ndarray  # (L, 3) the corners' unit normals
    loop_vertex: np.ndarray  # (L,) each corner's vertex
    vertex_count: int


@dataclass
class PendingBake:
    future: object  # resolves to a pipeline.PointLight for every corner of every target, in order
    targets: list
    skipped: list  # names of meshes left out (modifiers change their vertex count)
    method: str
    warnings: list = field(default_factory=list)
    started: float = field(default_factory=time.perf_counter)

    def elapsed(self) -> float:
        return time.perf_counter() - self.started


def corner_samples(obj, depsgraph) -> BakeTarget:
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.data
    nv, nl, nf = len(mesh.vertices), len(mesh.loops), len(mesh.polygons)
    co, loop_vertex = np.empty(nv * 3, np.float32), np.empty(nl, np.int64)
    mesh.vertices.foreach_get("co", co)
    mesh.loops.foreach_get("vertex_index", loop_vertex)
    centres, sizes = np.empty(nf * 3, np.float32), np.empty(nf, np.int64)
    mesh.polygons.foreach_get("center", centres)
    mesh.polygons.foreach_get("loop_total", sizes)
    nrm = np.empty(nl * 3, np.float32)
    mesh.corner_normals.foreach_get("vector", nrm)
    m = np.array(ev.matrix_world, np.float64)

    def world(p):
        return p.astype(np.float64) @ m[:3, :3].T + m[:3, 3]

    normal = nrm.reshape(-1, 3) @ np.linalg.inv(m[:3, :3])  # the inverse transpose, applied to row vectors
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    return BakeTarget(obj, world(co.reshape(-1, 3)[loop_vertex]), world(np.repeat(centres.reshape(-1, 3), sizes, 0)),
                      normal, loop_vertex, nv)


def evaluation_points(target: BakeTarget, inset: float) -> np.ndarray:
    """The corners moved `inset` metres toward their face's centre (at most INSET_LIMIT of the way)."""
    toward = target.centres - target.positions
    dist = np.linalg.norm(toward, axis=1, keepdims=True)
    step = np.minimum(inset, INSET_LIMIT * dist) / np.maximum(dist, 1e-12)
    return target.positions + toward * step


def method_cell(scene_data, settings) -> float:
    """The cell size of the method's voxel grid over the scene (0 for method "none")."""
    from ..gpu_kernels.common.grid import Grid

    method = getattr(settings, settings.method, None)
    if method is None or not hasattr(method, "resolution"):
        return 0.0
    lo, hi = scene_data.bounds()
    return Grid.fit(lo, hi, method.resolution, margin_cells=1).cell


def per_vertex(values: np.ndarray, loop_vertex: np.ndarray, count: int) -> np.ndarray:
    """The mean over each vertex's corners of per-corner values (L, C) → (V, C)."""
    total = np.zeros((count, values.shape[1]))
    np.add.at(total, loop_vertex, values)
    return (total / np.maximum(np.bincount(loop_vertex, minlength=count), 1)[:, None]).astype(np.float32)


def vertex_albedo(obj) -> np.ndarray:
    """(V, 3): per vertex, the mean base colour of the materials of the faces around it (a material's constant
    colour, or the Principled/Diffuse node's Base Color default; textures are not sampled)."""
    mesh = obj.data
    colors = np.array([material_color(slot.material) for slot in obj.material_slots] or [(0.8, 0.8, 0.8)],
                      np.float32)
    loop_vertex = np.empty(len(mesh.loops), np.int64)
    mesh.loops.foreach_get("vertex_index", loop_vertex)
    face_material, sizes = np.empty(len(mesh.polygons), np.int64), np.empty(len(mesh.polygons), np.int64)
    mesh.polygons.foreach_get("material_index", face_material)
    mesh.polygons.foreach_get("loop_total", sizes)
    loop_color = colors[np.clip(np.repeat(face_material, sizes), 0, len(colors) - 1)]
    return per_vertex(loop_color, loop_vertex, len(mesh.vertices))


def material_color(material) -> tuple:
    if material is None:
        return (0.8, 0.8, 0.8)
    if material.use_nodes and material.node_tree:
        for node in material.node_tree.nodes:
            for name in ("Base Color", "Color"):
                if node.type in ("BSDF_PRINCIPLED", "BSDF_DIFFUSE") and name in node.inputs:
                    return tuple(node.inputs[name].default_value)[:3]
    return tuple(material.diffuse_color)[:3]


def write_attribute(mesh, values: np.ndarray) -> None:
    """Values (V, 3) into the mesh's "BounceGI" FLOAT_COLOR point attribute (made, or re-made if it has another
    type or domain)."""
    attr = mesh.color_attributes.get(ATTRIBUTE)
    if attr is not None and (attr.domain != "POINT" or attr.data_type != "FLOAT_COLOR"):
        mesh.color_attributes.remove(attr)
        attr = None
    if attr is None:
        attr = mesh.color_attributes.new(ATTRIBUTE, "FLOAT_COLOR", "POINT")
    rgba = np.ones((len(values), 4), np.float32)
    rgba[:, :3] = values
    attr.data.foreach_set("color", rgba.ravel())
    mesh.update()


def bake_settings(settings):
    """The RenderSettings a bake runs: the render's, with the LPV's RSM BAKE_RSM_SCALE times as fine."""
    if settings.method != "lpv":
        return settings
    return replace(settings, lpv=replace(settings.lpv, rsm_resolution=BAKE_RSM_SCALE * settings.lpv.rsm_resolution))


def bake_objects(context, selected_only: bool) -> list:
    """The mesh objects to bake: visible in the view layer and rendered (and selected, if asked)."""
    objs = context.selected_objects if selected_only else context.view_layer.objects
    return [o for o in objs if o.type == "MESH" and o.visible_get() and not o.hide_render]


def start_bake(context, selected_only: bool) -> PendingBake:
    """Collect the corners of every mesh to bake, extract the scene and submit one GPU job; returns at once."""
    from ..addon.extract import ExtractError, extract_scene
    from ..gpu_kernels.engine import get_engine

    depsgraph = context.evaluated_depsgraph_get()
    targets, skipped = [], []
    for obj in bake_objects(context, selected_only):
        target = corner_samples(obj, depsgraph)
        (targets if target.vertex_count == len(obj.data.vertices) else skipped).append(target)
    if not targets:
        among = " among the selected objects" if selected_only else ""
        raise PreviewError(f"Bounce GI bake: no visible mesh to bake{among}")
    try:
        scene_data = extract_scene(depsgraph, EXTRACT_SIZE, require_camera=False)
    except ExtractError as ex:
        raise PreviewError(one_line(ex)) from None
    settings = bake_settings(render_settings_of(context.scene.bounce_gi, *EXTRACT_SIZE)[0])
    inset = INSET_CELLS.get(settings.method, 0.0) * method_cell(scene_data, settings)
    positions = np.concatenate([evaluation_points(t, inset) for t in targets]).astype(np.float32)
    normals = np.concatenate([t.normals for t in targets]).astype(np.float32)
    try:
        future = get_engine().submit_points(scene_data, settings, positions, normals)
    except Exception as ex:
        raise PreviewError(f"Bounce GI bake failed: {one_line(ex)}") from None
    return PendingBake(future, targets, [t.obj.name for t in skipped], settings.method, list(scene_data.warnings))


def finish_bake(pending: PendingBake, include_direct: bool = False, include_albedo: bool = False) -> dict:
    """Wait for the GPU job and write every target's attribute; a summary for the report."""
    light = wait_result(pending)  # PreviewError, one line, for a failed or cancelled job
    values, first = [], 0
    for t in pending.targets:  # every value first, then the writes: a failure writes nothing
        corners = light.indirect[first:first + len(t.positions)]
        if include_direct:
            corners = corners + light.direct[first:first + len(t.positions)]
        part = per_vertex(corners, t.loop_vertex, t.vertex_count)
        values.append(part * vertex_albedo(t.obj) if include_albedo else part)
        first += len(t.positions)
    for t, v in zip(pending.targets, values):
        write_attribute(t.obj.data, v)
    return {"meshes": len(pending.targets), "vertices": sum(t.vertex_count for t in pending.targets),
            "skipped": pending.skipped, "seconds": pending.elapsed(), "gpu_seconds": light.timings.get("total", 0.0),
            "method": pending.method, "warnings": list(dict.fromkeys([*pending.warnings, *light.warnings]))}
