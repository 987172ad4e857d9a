# SPDX-License-Identifier: GPL-3.0-or-later
"""The tessellation voxelisation's CPU side (voxel/voxelize.py mode="tessellation", Freed 2018, §4.1.2, after Fei et
al. 2012): triangles split so none needs a tessellation level above the hardware's, the patch buffer cut into draws
llvmpipe handles, and the vertex + tessellation + geometry program (no fragment stage) of voxel/tess.glsl."""
from __future__ import annotations

import numpy as np

from ..common.grid import Grid
from ..direct.geometry import bind_material
from ..gl import preprocessor as spp
from ..gl.bind import set_uniforms
from ..scene import Scene

MAX_TESS_LEVEL = 64          # GL_MAX_TESS_GEN_LEVEL is at least 64 everywhere (and exactly 64 on llvmpipe)
TESS_VERTEX_BUDGET = 16384   # tessellated vertices per draw call (half of what llvmpipe handles, see below)


def split_for_tessellation(positions: np.ndarray, cell: float, supersample: int,
                           max_level: int = MAX_TESS_LEVEL) -> tuple[np.ndarray, np.ndarray]:
    """Freed 2018, §4.1.2 / §5.2.2 footnote 3: split triangles whose longest edge needs a tessellation level above
    `max_level` (level = ceil(edge / cell · supersample)) into m² congruent sub-triangles (m = ceil(level /
    max_level)), so none needs more than the hardware gives. Returns (source triangle index, barycentric corner
    weights (S, 3, 3)) per output triangle, sources in input order; orientation is preserved."""
    need = np.ceil(_longest_edge(positions) / float(cell) * supersample)  # the level the control shader wants
    m = np.maximum(1, np.ceil(need / max_level)).astype(np.int64)
    src, bary = [], []
    for mm in np.unique(m):
        idx = np.flatnonzero(m == mm)
        lat = _lattice(int(mm))
        src.append(np.repeat(idx, len(lat)))
        bary.append(np.tile(lat, (len(idx), 1, 1)))
    if not src:
        return np.zeros(0, np.int64), np.zeros((0, 3, 3))
    src, bary = np.concatenate(src), np.concatenate(bary)
    order = np.argsort(src, kind="stable")
    return src[order], bary[order]


def _lattice(m: int) -> np.ndarray:
    """Barycentric weights (m², 3 corners, 3 weights) of the regular m-subdivision of a triangle."""
    tris = []
    for i in range(m):
        for j in range(m - i):
            tris.append([(i, j), (i + 1, j), (i, j + 1)])
            if i + j <= m - 2:
                tris.append([(i + 1, j), (i + 1, j + 1), (i, j + 1)])
    ij = np.asarray(tris, np.float64) / m                       # (m², 3, 2): weights of corners 1 and 2
    return np.concatenate([1.0 - ij.sum(axis=2, keepdims=True), ij], axis=2)


def tessellation_levels(positions: np.ndarray, cell: float, supersample: int) -> np.ndarray:
    """Per triangle, the inner level voxel/tess.glsl's control shader will pick (max edge level, ≤ 64)."""
    return np.clip(np.ceil(_longest_edge(positions) / float(cell) * supersample), 1, MAX_TESS_LEVEL)


def _longest_edge(positions: np.ndarray) -> np.ndarray:
    p = np.asarray(positions, np.float64).reshape(-1, 3, 3)
    return np.linalg.norm(p[:, [1, 2, 0]] - p, axis=2).max(axis=1)


def patch_buffers(ctx, scene: Scene, grid: Grid, supersample: int):
    """The patch VBO (same 11-float layout as direct/geometry.upload_geometry; normals unused) with oversized triangles
    split, grouped by material, and draw ranges cut so no draw generates more than TESS_VERTEX_BUDGET vertices.

    Why the cut: Mesa 22.3.6 llvmpipe's tessellator (measured here) hands the geometry shader sub-triangles made
    of the wrong vertices once one draw generates more than about 32768 tessellated vertices (measured: identical
    level-64 patches go wrong from the 12th in one draw; areas then come out several times too large).
    """
    src, bary = split_for_tessellation(scene.positions, grid.cell, supersample)
    order = np.argsort(scene.material_index[src], kind="stable")
    src, bary = src[order], bary[order]
    pos = np.einsum("scw,swd->scd", bary, np.asarray(scene.positions, np.float64)[src])
    uvs = np.einsum("scw,swd->scd", bary, np.asarray(scene.uvs, np.float64)[src])
    data = np.zeros((len(src), 3, 11), np.float32)
    data[..., 0:3], data[..., 6:8] = pos, uvs
    # Upper bound on tessellated vertices per patch at level n (3169 measured at n = 64, 61 at n = 8).
    n = tessellation_levels(pos, grid.cell, supersample)
    cost = np.cumsum(0.78 * n * n + 3.0 * n + 3.0)
    mats = scene.material_index[src]
    ranges = []
    starts = np.flatnonzero(np.r_[True, mats[1:] != mats[:-1]]) if len(mats) else np.zeros(0, int)
    for s, e in zip(starts, np.r_[starts[1:], len(mats)]):
        while s < e:
            base = cost[s - 1] if s > 0 else 0.0
            stop = max(s + 1, min(e, int(np.searchsorted(cost, base + TESS_VERTEX_BUDGET, side="right"))))
            ranges.append((int(mats[s]), int(s) * 3, int(stop - s) * 3))
            s = stop
    return ctx.buffer(data.tobytes() or b"\0" * 44), ranges




def draw_tessellated(ctx, programs, scene, buffers, textures, uniforms) -> None:
    import moderngl

    vbo, ranges = buffers
    prog = tessellation_program(programs, "voxel/tess.glsl")
    set_uniforms(prog, {**uniforms, "u_max_level": float(MAX_TESS_LEVEL)})
    vao = ctx.vertex_array(prog, [(vbo, "3f 12x 2f 12x", "in_position", "in_uv")])
    fbo = ctx.empty_framebuffer((1, 1))   # draws need a complete framebuffer even with the rasteriser off
    ctx.enable(moderngl.RASTERIZER_DISCARD)   # §4.1.2: no rasterisation; the geometry shader writes the voxels
    try:
        fbo.use()
        ctx.patch_vertices = 3
        for mat_index, first, count in ranges:
            bind_material(prog, scene, mat_index, textures)
            vao.render(moderngl.PATCHES, vertices=count, first=first)
    finally:
        ctx.disable(moderngl.RASTERIZER_DISCARD)
        vao.release()
        fbo.release()


_TESS_STAGES = (("vertex_shader", "VERTEX_SHADER"), ("tess_control_shader", "TESS_CONTROL_SHADER"),
                ("tess_evaluation_shader", "TESS_EVALUATION_SHADER"), ("geometry_shader", "GEOMETRY_SHADER"))


def tessellation_program(programs, name: str, defines: dict | None = None):
    """Compile a vertex + tessellation + geometry program (no fragment stage) from one .glsl file.

    ProgramCache/gl.preprocessor only know vertex/fragment/geometry/compute stages, so the stage macro is
    injected as an ordinary define (every stage then has the same header length, so one line map serves the
    error report). The program is stored in the ProgramCache's table so `programs.release()` frees it.
    """
    table = getattr(programs, "_programs", None)
    if table is None:
        table = programs.__dict__.setdefault("_voxelize_programs", {})
    key = ("tessellation", name, tuple(sorted((defines or {}).items())))
    if key not in table:
        stages = {arg: spp.load(name, {**(defines or {}), macro: None}) for arg, macro in _TESS_STAGES}
        try:
            table[key] = programs.ctx.program(**{arg: src.text for arg, src in stages.items()})
        except Exception as exc:  # moderngl raises a plain Error carrying the driver log
            raise spp.ShaderCompileError(spp.format_compile_error(str(exc), stages["vertex_shader"])) from None
    return table[key]
