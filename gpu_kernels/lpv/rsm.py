# SPDX-License-Identifier: GPL-3.0-or-later
"""Reflective shadow maps (Dachsbacher and Stamminger 2005, "Reflective Shadow Maps"): every shadow view of every
light rendered once more as position, normal and albedo, the texels the VPLs are made from."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..common import atlas
from ..common import lights as lb
from ..direct.geometry import SURFACE_MATERIAL, draw_by_material, material_batches, material_binding
from ..direct.shadows import redraw_plan
from ..gl.bind import set_uniform, ssbo, write_uniform
from ..scene import Scene


@dataclass
class Rsm:
    position: object
    normal: object
    albedo: object
    views_ssbo: object
    size: tuple
    resolution: int
    vao: object = None
    fbo: object = None
    depth: object = None
    tiles: list = None  # each view's tile (x, y, w, h)
    views: np.ndarray = None  # (N, 20) what each tile was drawn from (direct/shadows.view_rows)
    drawn: int = 0  # views drawn (whole or in part) when it was last made or updated
    drawn_from: tuple = None  # the scene's triangles it was drawn from: positions, normals, UVs, materials
    geometry: object = None  # the GeometryBuffers `vao` draws
    partial: int = 0  # of the views drawn, those drawn in a rectangle only (an object's move: moved_rects)
    # Updates drawn into this atlas since it was made, and what the last one drew: (view, rect or None for its
    # whole tile) per view, None where it was drawn anew — the texels the RSM's records must be made again from
    # (lpv/passes.texel_records).
    generation: int = 0
    redrawn: list = None

    def release(self):
        for obj in (self.position, self.normal, self.albedo, self.views_ssbo, self.fbo, self.depth, self.vao):
            if obj is not None:
                obj.release()


RSM_VIEW_DTYPE = np.dtype([("params", "<f4", 4), ("origin", "<f4", 4), ("axis", "<f4", 4), ("right", "<f4", 4)])


def flux_bound(buffers: lb.LightBuffers) -> float:
    """An upper bound of the flux all lights together can deliver to surfaces (W), for the fixed-point scale."""
    total = 0.0
    for i, rec in enumerate(buffers.lights):
        color = float(np.max(rec["color_type"][:3]))
        kind = int(rec["color_type"][3])
        if kind in (lb.LIGHT_SUN, lb.LIGHT_SKY):  # each view's square × its irradiance (a sky view's: L·Ω_k)
            views = [v for v, l in zip(buffers.views, buffers.view_lights) if l == i]
            total += sum(color * (v.emit_share if kind == lb.LIGHT_SKY else 1.0) * (2 * v.half_extent) ** 2
                         for v in views)
        elif kind in (lb.LIGHT_POINT, lb.LIGHT_SPOT):
            total += color * 4 * math.pi
        else:
            first, count, two_sided = int(rec["polygon"][0]), int(rec["polygon"][1]), rec["polygon"][2] > 0.5
            rows = buffers.polygon_vertices[first:first + count].astype(np.float64)
            if rec["polygon"][3] > 0.5:  # a triangle list: Σ area × its largest relative radiance
                t = rows.reshape(-1, 4, 4)
                areas = 0.5 * np.linalg.norm(np.cross(t[:, 1, :3] - t[:, 0, :3], t[:, 2, :3] - t[:, 0, :3]), axis=1)
                area = float((areas * t[:, 3, :3].max(axis=1)).sum())
            else:
                p = rows[:, :3]
                area = 0.5 * np.linalg.norm(sum(np.cross(p[j], p[(j + 1) % count]) for j in range(count)))
            total += color * math.pi * area * (2 if two_sided else 1)
    return max(total, 1e-12)


def view_resolution(resolution: int, ortho: bool, samples: int, width: float = 0.0, texel: float = 0.0) -> int:
    """Texels per side of one RSM view: `resolution` (a sun's map twice that). A light sampled from several points
    (an area light's samples, each its own view of the same surfaces) splits its flux between them, and each of
    its texels' flux loops over every sample (lpv/inject.glsl); so each view gets 1/samples of the side, which
    keeps the light's work about one view's worth — the views together still cover its surfaces densely. An
    orthographic view `width` metres across needs texels no finer than `texel` (> 0): its texels' flux is binned
    into surface voxels (lpv/clusters.bin_flux), and a texel much smaller than one only costs time (a sun's 256²
    over a 25 m courtyard was 4 times what the voxels resolve, and most of a light edit there). A multiple of 16
    (lpv/inject.glsl's blocks never straddle views)."""
    side = resolution * (2 if ortho else 1)
    if ortho and width > 0.0 and texel > 0.0:
        side = min(side, max(16, 16 * math.ceil(width / texel / 16)))
    if samples > 1:
        side = max(16, 16 * round(side / samples / 16))
    return side


def render_rsm(ctx, programs, scene: Scene, geometry, textures, shadows, resolution: int, texel: float = 0.0,
               prior: Rsm | None = None) -> Rsm:
    """Render every shadow view of every light once more as an RSM (position, normal, albedo) into an atlas.
    `texel` (m, > 0): the finest texel an orthographic view needs (view_resolution). With `prior` (the RSM of the
    same textures, tiled alike) only what changed is drawn again, into `prior`, which is returned updated, as
    direct/shadows.render_depth does with the depth atlas: the views that changed (a light's move redraws its own),
    and where the scene's triangles moved, in every other view the rectangle they cover (moved_rects)."""
    import moderngl

    buffers = shadows.buffers
    views, view_lights = buffers.views, buffers.view_lights
    res = [view_resolution(resolution, v.ortho, int(buffers.lights[light]["params"][2]), 2 * v.half_extent, texel)
           for v, light in zip(views, view_lights)]
    tiles, size, scale = atlas.allocate_atlas(res, max_height=ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384))
    tiles, size, rows = [tuple(t) for t in tiles], tuple(size), shadows.rows
    surfaces = scene.surface_arrays()  # what its texels hold
    plan = redraw_plan(prior, views, tiles, size, rows, surfaces)
    out = prior if plan is not None else _new_rsm(ctx, programs, geometry, size, resolution // scale)
    if out.geometry is not geometry:  # the geometry's buffers were made again: draw from the new ones
        out.vao.release()
        out.vao = _vertex_array(ctx, programs, geometry)
    draws = {i: None for i in range(len(views))} if plan is None else dict(plan)
    out.fbo.use()
    if plan is None:
        out.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.disable(moderngl.CULL_FACE)
    prog = programs.raster("lpv/rsm.glsl")
    batches = material_batches(scene, geometry, textures)  # the material index comes from each vertex
    bindings = {m: material_binding(prog, scene, m, textures) for m, _, _ in batches}
    records = np.zeros(len(views), RSM_VIEW_DTYPE)
    for i, (view, (x, y, w, h)) in enumerate(zip(views, tiles)):
        _view_record(records[i], view, view_lights[i], buffers.lights[view_lights[i]], i, w)
        if i not in draws:
            continue
        if plan is not None:
            out.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0, viewport=draws[i] or (x, y, w, h))
        if view.unlit:  # behind its light (lights.cube_views): left empty, so it makes no records
            continue
        out.fbo.viewport = (x, y, w, h)
        ctx.scissor = draws[i]  # None: the whole tile
        write_uniform(prog, "u_view_projection", view.view_projection.T)
        back = view.view_matrix[2, :3]  # rows of world → view: right, up, back
        set_uniform(prog, "u_origin", tuple(float(c) for c in view.origin))
        set_uniform(prog, "u_forward", tuple(float(c) for c in -back))
        set_uniform(prog, "u_ortho", bool(view.ortho))
        set_uniform(prog, "u_far", 0.0 if view.ortho else float(view.far))
        set_uniform(prog, "u_view_index", float(i))
        draw_by_material(prog, scene, geometry, textures, vao=out.vao, bindings=bindings, batches=batches)
    ctx.scissor = None
    if out.views_ssbo is not None and out.views_ssbo.size == records.nbytes:
        out.views_ssbo.write(records.tobytes())
    else:
        if out.views_ssbo is not None:
            out.views_ssbo.release()
        out.views_ssbo = ssbo(ctx, records)
    out.tiles, out.views, out.drawn = tiles, rows, len(draws)
    out.drawn_from, out.geometry, out.partial = surfaces, geometry, sum(r is not None for r in draws.values())
    out.generation, out.redrawn = (out.generation + 1, list(draws.items())) if plan is not None else (0, None)
    return out


def _new_rsm(ctx, programs, geometry, size: tuple, resolution: int) -> Rsm:
    """An empty RSM atlas of `size` texels: position, normal and albedo targets, a depth buffer, the VAO it is
    drawn with."""
    import moderngl

    targets = [ctx.texture(size, 4, dtype="f4") for _ in range(3)]
    for t in targets:
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    depth = ctx.depth_renderbuffer(size)
    fbo = ctx.framebuffer(color_attachments=targets, depth_attachment=depth)
    return Rsm(*targets, None, size, resolution, _vertex_array(ctx, programs, geometry), fbo, depth,
               geometry=geometry)


def _vertex_array(ctx, programs, geometry):
    """The VAO lpv/rsm.glsl draws `geometry`'s vertex buffer with."""
    prog = programs.raster("lpv/rsm.glsl")
    return ctx.vertex_array(prog, [(geometry.vbo, SURFACE_MATERIAL, "in_position", "in_normal", "in_uv",
                                    "in_geo_normal", "in_material")])


def _view_record(record, view, light: int, light_record, index: int, w: int) -> None:
    """One view's RSM_VIEW_DTYPE record: its projection's extent, eye, axis and the light (and sample) it
    belongs to."""
    right, back = view.view_matrix[0, :3], view.view_matrix[2, :3]  # rows of world → view: right, up, back
    k = (index - int(light_record["params"][1])) // max(int(light_record["params"][3]), 1)
    record["params"] = (0.0 if view.ortho else view.half_extent, 2 * view.half_extent / w if view.ortho else 0.0,
                        light, k)
    record["origin"] = (*view.origin, 1.0 if view.ortho else 0.0)
    record["axis"] = (*-back, float(w))  # w: texels per side of this view
    record["right"] = (*right, view.own_extent)

