# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's gathered transport (LpvSettings.transport = "gather", the default): light goes straight from lists of
VPLs to the surface voxels of the geometry volume, with fuzzy visibility through it (lpv/gather.glsl), instead of
through the Kaplanyan–Dachsbacher propagation. The VPLs are instant radiosity's (Keller 1997); lpv/gather.glsl walks the
cells between a VPL and a voxel with the traversal of Amanatides and Woo 1987.

Why: the face scheme re-emits, at every cell, what each face received as a cosine lobe toward that face; a lobe
pointing up keeps only 0.096 of its flux going up (the rest turns sideways), so light from a lit floor returns to
the floor instead of reaching the ceiling — Cornell box DI rel-L1 0.69, ceiling at 0.14× Cycles. The gather keeps
the LPV's pieces (RSM VPLs with their injection's flux, the geometry volume's surface voxels, their absorbed
irradiance that the flux lookup reads and the next bounce reflects) and replaces only the transport:

- first bounce: the RSM texels, clustered k×k into at most `gather_vpls` VPLs (`vpl_list`);
- each further bounce: the light the surface voxels reflect, clustered into S×S×S blocks (`bounce_vpls`);
- world light is the sky light's VPLs, gathered like any other light's.

Cost: voxels × VPLs × (distance / cell) samples per bounce — independent of the propagation's iteration count.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.bounce_tail import tail_ratio, tail_sum
from ..common.grid import Grid
from ..gl.bind import bind_grid, bind_light_records, bind_named, dispatch, set_uniform, ssbo, zero_texture
from .crossings import bind_visibility
from .occlusion import absorb
from .settings import LpvSettings
from .state import LpvGridState

VPL_DTYPE = np.dtype([("position", "<f4", 4), ("normal", "<f4", 4), ("flux", "<f4", 4)])
MAX_BLOCK = 16  # RSM texels per VPL side (tiles are multiples of 16) and fine voxels per cluster side
PRECLUSTER = 64  # the GPU clusters blocks until at most this many slots per VPL of the budget are read back


@dataclass
class VplList:
    """VPLs as a storage buffer of VPL_DTYPE records: position (w = 1), unit normal (w = area or 0), rgb flux."""
    buffer: object
    count: int
    flux_rgb: tuple  # total flux per channel (W)
    block: int  # k: RSM texels, or S: fine voxels, per VPL side

    @property
    def flux(self) -> float:
        """Total flux, sum of RGB (W)."""
        return float(sum(self.flux_rgb))

    def release(self):
        self.buffer.release()


def rsm_uniforms(prog, rsm, shadows, materials, downsample: int, change: tuple | None = None) -> tuple:
    """Bind what lpv/inject.glsl reads of the RSM, the materials (direct/geometry.MaterialTextures: the Principled
    table and base colours) and the lights; returns the atlas size in k×k blocks. `change`: two storage buffers of
    base_colors rows, (new, old; old's w = 1 where a material's colour changed): the texels' flux is the change."""
    bind_named(prog, [("u_rsm_position", rsm.position), ("u_rsm_normal", rsm.normal), ("u_rsm_albedo", rsm.albedo),
                      ("u_material_lut", materials.lut)])
    new, old = change or (materials.colors_ssbo, materials.colors_ssbo)
    new.bind_to_storage_buffer(8)
    old.bind_to_storage_buffer(10)
    set_uniform(prog, "u_delta", change is not None)
    set_uniform(prog, "u_rsm_size", rsm.size)
    set_uniform(prog, "u_downsample", int(downsample))
    bind_light_records(shadows)
    rsm.views_ssbo.bind_to_storage_buffer(3)
    return (rsm.size[0] + downsample - 1) // downsample, (rsm.size[1] + downsample - 1) // downsample


def _collect(ctx, slots: int, run, with_slots: bool = False):
    """Run a VPL-writing pass into `slots` zeroed records (binding 6) and keep the ones it wrote (w = 1); with
    `with_slots`, (those records, their slots)."""
    buf = ctx.buffer(reserve=max(slots, 1) * VPL_DTYPE.itemsize)
    buf.clear()
    buf.bind_to_storage_buffer(6)
    run()
    records = np.frombuffer(buf.read(), VPL_DTYPE)
    buf.release()
    written = records["position"][:, 3] > 0.5
    return (records[written], np.nonzero(written)[0]) if with_slots else records[written]


def merge(records: np.ndarray, size: float) -> np.ndarray:
    """Merge VPLs that share a cube of side `size` and a dominant normal direction (±x, ±y, ±z: a floor and the
    wall beside it stay apart): flux and area add up, position and normal are luminance-weighted means — flux is
    kept exactly. Also merges across RSM views (an area light's sample points each see the same floor)."""
    pos, normal, flux = records["position"][:, :3], records["normal"][:, :3], records["flux"][:, :3]
    axis = np.argmax(np.abs(normal), axis=1)
    side = 2 * axis + (normal[np.arange(len(normal)), axis] < 0)
    cube = np.floor(pos / size).astype(np.int64)
    cube -= cube.min(axis=0)
    span = cube.max(axis=0) + 1
    key = ((cube[:, 0] * span[1] + cube[:, 1]) * span[2] + cube[:, 2]) * 6 + side
    _, group = np.unique(key, return_inverse=True)
    groups = int(group.max()) + 1
    w = np.maximum(flux.astype(np.float64) @ (0.2126, 0.7152, 0.0722), 1e-30)

    def total(values):
        return np.stack([np.bincount(group, values[:, i], groups) for i in range(values.shape[1])], axis=1)

    out = np.zeros(groups, VPL_DTYPE)
    wsum = np.bincount(group, w, groups)[:, None]
    out["position"][:, :3] = total(pos * w[:, None]) / wsum
    out["position"][:, 3] = 1.0
    n = total(normal * w[:, None])
    out["normal"][:, :3] = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    out["normal"][:, 3] = np.bincount(group, records["normal"][:, 3].astype(np.float64), groups)
    out["flux"][:, :3] = total(flux.astype(np.float64))
    return out


def _fitted(ctx, records: np.ndarray, size: float, block: int, budget: int) -> VplList:
    """`records` merged (`merge`) in cubes of side `size`, doubled until at most `budget` VPLs remain."""
    while len(records) > budget:
        records = merge(records, size)
        size *= 2
    payload = records.tobytes() if len(records) else np.zeros(1, VPL_DTYPE).tobytes()
    flux = tuple(float(c) for c in records["flux"][:, :3].astype(np.float64).sum(axis=0))
    return VplList(ctx.buffer(payload), len(records), flux, block)


def rsm_records(ctx, programs, rsm, shadows, materials, grid: Grid, budget: int, limit: int | None = None,
                unit_color: bool = False, lights: np.ndarray | None = None,
                change: tuple | None = None, blocks: np.ndarray | None = None, with_slots: bool = False) -> tuple:
    """The RSM as VPL records (VPL_DTYPE) and k: k×k texel blocks (intensity-aware, lpv/inject.glsl MODE_LIST), k the
    smallest power of two whose blocks number at most `limit` (default a few times `budget`: much of an atlas is
    empty, a sun's map covers the whole grid, a spot's cone a disc; block_size). A block spanning two surfaces gives
    two VPLs; the grid's cell sets the plane tolerance. Each record's flux.w is its light's index; with `unit_color`
    its flux is per unit of that light's colour (the flux a colour of 1 would give). `lights` (bool per light): only
    those lights' texels make records (the same records, in the same order, as without it). `change` (new, old: two
    arrays of direct/geometry.base_colors rows, old's w = 1 where a material's colour changed): the records' flux is
    what the texels of the changed materials reflect at the new colours less at the old (positions and normals alike:
    they do not depend on the colours), and only the records with a change are returned. `blocks` (covered_blocks):
    only those blocks make records, the same ones the whole atlas gives there. With `with_slots`, (records, k,
    slots): each record's slot in the whole atlas's list, 2 × (block row × blocks per row + block column) + its
    plane, the order a run over the whole atlas lists them in (merge_records)."""
    k = block_size(rsm, PRECLUSTER * budget if limit is None else limit)
    prog = programs.compute("lpv/inject.glsl", {"MODE_LIST": 1, **({"BLOCK_LIST": 1} if blocks is not None else {}),
                                                **shadows.defines})
    bind_grid(prog, grid)
    set_uniform(prog, "u_unit_color", bool(unit_color))
    set_uniform(prog, "u_masked", lights is not None)
    buffers = [ssbo(ctx, np.asarray([] if lights is None else lights, np.uint32))]
    buffers[0].bind_to_storage_buffer(7)
    if change is not None:
        buffers += [ssbo(ctx, np.asarray(c, np.float32)) for c in change]
    size = rsm_uniforms(prog, rsm, shadows, materials, k, tuple(buffers[1:]) if change is not None else None)
    set_uniform(prog, "u_blocks_x", int(size[0]))
    if blocks is not None:  # listed: one dispatch, block i's records in slots 2i and 2i + 1
        rows, columns = np.nonzero(blocks.reshape(size[1], size[0]))
        buffers.append(ssbo(ctx, np.stack([columns, rows], axis=1).astype(np.int32)))
        buffers[-1].bind_to_storage_buffer(11)
        set_uniform(prog, "u_list_count", len(rows))
        records, index = _collect(ctx, 2 * len(rows), lambda: dispatch(prog, (-(-len(rows) // 64),), local=1),
                                  with_slots=True)
        index = 2 * (rows[index // 2] * size[0] + columns[index // 2]) + index % 2
    else:
        records, index = _records_in_bands(ctx, prog, rsm, shadows, lights, k, size)
    for buf in buffers:
        buf.release()
    if change is not None:
        keep = np.any(records["flux"][:, :3] != 0.0, axis=1)
        records, index = records[keep], index[keep]
    return (records, k, index) if with_slots else (records, k)


def block_size(rsm, limit: int) -> int:
    """k of rsm_records: the smallest power of two (up to MAX_BLOCK) whose k×k blocks of the atlas number at most
    `limit` — clustered on the GPU first, so that the read-back stays a few times the budget."""
    k = 1
    while k < MAX_BLOCK and -(-rsm.size[0] // k) * -(-rsm.size[1] // k) > limit:
        k *= 2
    return k


def _records_in_bands(ctx, prog, rsm, shadows, lights, k: int, size: tuple) -> tuple:
    """rsm_records over the whole atlas, or (`lights`) the rows of those lights' views: (records, their slots in
    the whole atlas's list)."""
    boxes = [(0, 0, size[0], size[1])] if lights is None else [
        (x // k, y // k, -(-w // k), -(-h // k)) for (x, y, w, h), light in zip(rsm.tiles, shadows.buffers.view_lights)
        if lights[light]]
    bands = _bands([(y, y + h) for _, y, _, h in boxes])
    firsts = np.cumsum([0] + [2 * size[0] * (y1 - y0) for y0, y1 in bands])

    def run():
        for (y0, y1), base in zip(bands, firsts):  # each band of block rows from its own slot on, in row order
            set_uniform(prog, "u_row_base", int(y0))
            set_uniform(prog, "u_slot_base", int(base))
            for bx, by, bw, bh in boxes:
                if y0 <= by < y1:
                    set_uniform(prog, "u_block_origin", (int(bx), int(by)))
                    set_uniform(prog, "u_block_count", (int(bw), int(bh)))
                    dispatch(prog, (bw, bh), local=8)
    records, index = _collect(ctx, int(firsts[-1]), run, with_slots=True)
    # a band's slot s, from slot `base` on for its rows from y0 on, is the whole atlas's s − base + 2·y0·blocks_x
    band = np.searchsorted(firsts, index, side="right") - 1
    starts = np.array([y0 for y0, _ in bands] or [0], np.int64)
    return records, index - firsts[band] + 2 * size[0] * starts[band]


def covered_blocks(rects: list, k: int, size: tuple) -> np.ndarray:
    """(blocks_y × blocks_x,) bool, row-major: the k×k blocks of an atlas of `size` blocks that the texel
    rectangles `rects` (x, y, w, h) touch."""
    out = np.zeros((size[1], size[0]), bool)
    for x, y, w, h in rects:
        out[y // k:-(-(y + h) // k), x // k:-(-(x + w) // k)] = True
    return out.ravel()


def merge_records(old: tuple, new: tuple, redone: np.ndarray) -> tuple:
    """(records, slots) of the whole atlas from `old` (records, slots) of it as it was and `new` of only the blocks
    `redone` marks (covered_blocks; rsm_records with them, after those texels were drawn again): old's records
    outside those blocks, new's inside, in slot order — what a run over the whole atlas gives, when nothing else
    changed."""
    keep = ~redone[old[1] // 2]
    records = np.concatenate([old[0][keep], new[0]])
    slots = np.concatenate([old[1][keep], new[1]])
    order = np.argsort(slots, kind="stable")
    return records[order], slots[order]


def _bands(spans: list) -> list:
    """Half-open row ranges [y0, y1) merged where they overlap or touch, in increasing order."""
    out = []
    for y0, y1 in sorted(spans):
        if out and y0 <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], y1))
        else:
            out.append((y0, y1))
    return out


def vpl_list(ctx, programs, rsm, shadows, materials, grid: Grid, budget: int) -> VplList:
    """The RSM as at most `budget` VPLs: rsm_records merged (`merge`) until they fit."""
    records, k = rsm_records(ctx, programs, rsm, shadows, materials, grid, budget)
    return _fitted(ctx, records, grid.cell / 2, k, budget)


def bounce_vpls(ctx, programs, state: LpvGridState, gv, budget: int) -> VplList:
    """The light the surface voxels reflect (albedo × last pass's irradiance × area, per side) as at most `budget`
    VPLs: S×S×S voxel blocks, up to three per block split by plane (lpv/cluster.glsl), S from 2 up."""
    prog = programs.compute("lpv/cluster.glsl")
    bind_named(prog, [("u_front", state.front), ("u_back", state.back), ("u_voxel_normal", gv.normal),
                      ("u_voxel_area", gv.area), ("u_voxel_albedo", gv.albedo),
                      ("u_voxel_albedo_back", gv.albedo_back or gv.albedo)])
    set_uniform(prog, "u_fine_origin", tuple(float(c) for c in gv.fine.origin))
    set_uniform(prog, "u_fine_size", tuple(gv.fine.size))
    set_uniform(prog, "u_voxel", float(gv.fine.cell))

    block = 1
    while block < MAX_BLOCK and 3 * np.prod([-(-n // block) for n in gv.fine.size]) > PRECLUSTER * budget:
        block *= 2
    blocks = tuple(-(-n // block) for n in gv.fine.size)
    set_uniform(prog, "u_block", int(block))
    set_uniform(prog, "u_blocks", blocks)
    records = _collect(ctx, 3 * int(np.prod(blocks)), lambda: dispatch(prog, blocks))
    return _fitted(ctx, records, gv.fine.cell * block, block, budget)


def extrapolate_tail(ctx, programs, state: LpvGridState, gv, tail) -> None:
    """Add this pass's front/back irradiance × `tail` (RGB) to the totals (lpv/tail.glsl)."""
    prog = programs.compute("lpv/tail.glsl")
    for unit, name in enumerate(("front", "back", "front_total", "back_total")):
        getattr(state, name).bind_to_image(unit, read=True, write=unit >= 2)
    set_uniform(prog, "u_size", tuple(gv.fine.size))
    set_uniform(prog, "u_tail", tuple(float(t) for t in tail))
    dispatch(prog, gv.fine.size)


def vpls_per_dispatch(grid: Grid) -> int:
    """VPLs one gather dispatch takes. llvmpipe stops a shader invocation's loops after 65535 iterations in all
    (LP_MAX_TGSI_LOOP_ITERATIONS, shared between every loop of a shader): past it the gather silently dropped the
    later VPLs' light. A VPL costs at most one visibility step per cell a straight line can visit (nx + ny + nz +
    3) plus its near-field quarter discs; half the limit leaves room for the rest."""
    return max(1, 32768 // (sum(int(n) for n in grid.size) + 8))


def gather(ctx, programs, state: LpvGridState, gv, vpls: VplList, occlusion: bool, fresh: bool) -> None:
    """Add the irradiance every surface voxel receives straight from `vpls` (lpv/gather.glsl) to this pass's front
    and back irradiance (cleared first when `fresh`: a further bounce's pass) and to their totals."""
    if fresh:
        zero_texture(ctx, state.front)
        zero_texture(ctx, state.back)
    if vpls.count == 0:
        return
    prog = programs.compute("lpv/gather.glsl")
    bind_visibility(prog, gv, bind_named(prog, [("u_voxel_normal", gv.normal), ("u_voxel_area", gv.area)]))
    set_uniform(prog, "u_occlusion", bool(occlusion))
    set_uniform(prog, "u_fine_origin", tuple(float(c) for c in gv.fine.origin))
    bind_grid(prog, state.grid)
    vpls.buffer.bind_to_storage_buffer(6)
    gv.surfaces.bind_to_storage_buffer(7)
    set_uniform(prog, "u_surface_count", int(gv.surface_count))
    for unit, name in enumerate(("front", "back", "front_total", "back_total")):
        getattr(state, name).bind_to_image(unit, read=True, write=True)
    chunk = vpls_per_dispatch(state.grid)
    for first in range(0, vpls.count, chunk):
        set_uniform(prog, "u_vpl_first", first)
        set_uniform(prog, "u_vpl_count", min(chunk, vpls.count - first))
        dispatch(prog, (gv.surface_count,), local=64)
        ctx.memory_barrier()


def gather_all(ctx, programs, states: list, gvs: list, settings: LpvSettings) -> dict:
    """The gathered transport, per cascade: the RSM's VPLs (state.vpls, the sky light's among them) and then,
    bounce by bounce, the light the surface voxels reflect are gathered straight to the surface voxels."""
    stats = []
    for state, gv in zip(states, gvs):
        state.face_flux.clear()
        absorb(ctx, programs, state, gv, add=False)  # zeros: the irradiance textures the gathers add to
        bounces = []
        gathered = min(settings.bounces, settings.gathered_bounces or settings.bounces)
        vpls = state.vpls
        for bounce in range(gathered):
            gather(ctx, programs, state, gv, vpls, settings.occlusion, fresh=bounce > 0)
            bounces.append({"vpls": vpls.count, "flux": vpls.flux, "block": vpls.block})
            if bounce > 0:
                vpls.release()
            if vpls.count == 0 or bounce + 1 == settings.bounces:
                break
            previous = vpls.flux_rgb
            vpls = bounce_vpls(ctx, programs, state, gv, settings.gather_vpls)
            if bounce + 1 == gathered:  # bounces gathered + 1 … N: extrapolated from the flux ratio
                vpls.release()
                ratio = tail_ratio(vpls.flux_rgb, previous)
                n = settings.bounces - gathered
                extrapolate_tail(ctx, programs, state, gv, tail_sum(ratio, n))
                bounces.append({"extrapolated": n, "ratio": [float(r) for r in ratio]})
        stats.append({"cells": list(state.grid.size), "cell": state.grid.cell,
                      "injected_flux": state.vpls.flux, "bounces": bounces})
    return {"cascades": stats}
