# SPDX-License-Identifier: GPL-3.0-or-later
"""Octree Light Propagation Volumes (Olovsson and Doggett 2013), an option of the LPV (`octree_levels`).

§3.1 A full octree: every level O_i (i = 0..l-1) is a uniform grid of its own (three RGBA32F 3D textures), O_0 the
    LPV grid, O_i = n/2^i cells of 2^i·cell, same origin. The index volume hierarchy I_i says which level to sample;
    S(x) = O_{I(x)}(x >> I(x)) with I(x) = min_i I_i(x >> i) (Eq. 1). Index rule (`index_hierarchy`): a level-i node
    is usable where it and its 26 neighbours (the cells its propagation reads, and the trilinear lookup's reach) hold
    no surface — coarse levels propagate through coarse, blurred occlusion and must not be read next to geometry.
    So I_i(p) = i−1 where that level-i neighbourhood holds a surface, else l−1 (the paper's initial value; I_0 ≡ l−1):
    I(x) is the coarsest level whose neighbourhood of x is empty, 0 at and next to geometry.
§3.2 Injection into O_0 as in the uniform LPV; downsampling into O_1.. by summing the eight children
    (lpv/octree_downsample.glsl: our state is flux per cell, for which Eq. 2's average is a sum — derived there).
§3.3 Propagation on every level with `octree_iterations` steps (k = 4 in the paper), each level blocked by its own
    geometry volume, downsampled from the O_0 voxelisation (`level_blocking`).
§3.4 Merge M(x) = S(x) into one O_0 volume of accumulated intensity (lpv/octree_merge.glsl: A_i/4^i, derived
    there), then the unchanged lighting step with Kaplanyan's intensity lookup (the flux lookup needs one grid's
    whole propagation history — see the merge shader). One bounce: later bounces re-inject the absorbed flux.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..common.grid import Grid
from ..gl.bind import bind_images, bind_named, bind_samplers, dispatch, set_uniform
from .occlusion import face_blocking
from .propagate import propagate
from .settings import LpvSettings
from .sh import SH_FLUX
from .state import LpvGridState, Volumes, copy_volumes, make_volumes

MAX_LEVELS = 5  # lpv/octree_merge.glsl


def level_grids(grid: Grid, levels: int) -> list[Grid]:
    """O_0..O_{l-1}: the same origin, cell 2^i·cell, ceil(n/2^i) cells (an odd level's last parent is half empty)."""
    return [Grid(grid.origin, grid.cell * 2 ** i, tuple(-(-n // 2 ** i) for n in grid.size)) for i in range(levels)]


def pool(fine0: np.ndarray, factor: int, shape: tuple, offset: int, reduce=np.sum) -> np.ndarray:
    """Blocks of factor³ voxels of a [z, y, x, ...] array: output j holds input [factor·j − offset, …+factor)."""
    pad = [(offset, max(0, factor * s - offset - n)) for s, n in zip(shape, fine0.shape[:3])]
    a = np.pad(fine0, pad + [(0, 0)] * (fine0.ndim - 3))[:factor * shape[0], :factor * shape[1], :factor * shape[2]]
    a = a.reshape(shape[0], factor, shape[1], factor, shape[2], factor, *fine0.shape[3:])
    return reduce(a, axis=(1, 3, 5))


def level_blocking(area0: np.ndarray, grids: list) -> list[np.ndarray]:
    """Face blocking of every level (GV downsampling): the projected areas of the O_0 surface voxels (half an O_0
    cell, origin − cell/2) summed into level-i surface voxels (half a level-i cell, origin − cell_i/2) — an exact
    regrouping, since level-i voxel j starts at O_0 voxel 2^i·j − (2^i − 1) — then the same box rule as O_0
    (lpv/occlusion.face_blocking). Level 0 reproduces the uniform LPV's blocking exactly."""
    out = []
    for i, g in enumerate(grids):
        f = 2 ** i
        shape = tuple(2 * n + 2 for n in g.size[::-1])
        out.append(face_blocking(pool(area0.astype(np.float64), f, shape, f - 1), g))
    return out


def _dilate(occ: np.ndarray) -> np.ndarray:
    """26-neighbourhood dilation of a boolean [z, y, x] volume."""
    p = np.pad(occ, 1)
    out = np.zeros_like(occ)
    z, y, x = occ.shape
    for dz in range(3):
        for dy in range(3):
            for dx in range(3):
                out |= p[dz:dz + z, dy:dy + y, dx:dx + x]
    return out


def index_hierarchy(area0: np.ndarray, grids: list) -> list[np.ndarray]:
    """I_0..I_{l-1} ([z, y, x] int arrays, §3.1): I_i(p) = i − 1 where level-i node p or one of its 26 neighbours
    holds a surface (surface area > 0 in the O_0 voxelisation), else l − 1 (I_0 ≡ l − 1)."""
    l = len(grids)
    n = grids[0].size[::-1]
    occ0 = area0[1:2 * n[0] + 1, 1:2 * n[1] + 1, 1:2 * n[2] + 1, 3].reshape(n[0], 2, n[1], 2, n[2], 2).sum(
        axis=(1, 3, 5)) > 0  # O_0 cell c holds surface voxels [2c+1, 2c+3)
    out = [np.full(n, l - 1, np.int32)]
    for i in range(1, l):
        occ = pool(occ0[..., None], 2 ** i, grids[i].size[::-1], 0, np.max)[..., 0]
        out.append(np.where(_dilate(occ), i - 1, l - 1).astype(np.int32))
    return out


def flatten_index(index: list[np.ndarray]) -> np.ndarray:
    """Eq. 1's level per O_0 cell: I(x) = min_i I_i(x >> i)."""
    n = index[0].shape
    out = index[0].copy()
    for i, level in enumerate(index[1:], 1):
        z, y, x = (np.arange(k) >> i for k in n)
        out = np.minimum(out, level[np.ix_(z, y, x)])
    return out


@dataclass
class OctreeGeometry:
    """Per-geometry octree data: level grids, per-level face blocking (level 0 is the GV's, not owned), I_i."""
    grids: list
    blocking: list
    index_textures: list
    index: list  # numpy I_i

    def release(self):
        for t in self.blocking[1:] + self.index_textures:
            t.release()


def build_geometry(ctx, gv, grid: Grid, levels: int) -> OctreeGeometry:
    """Downsampled geometry volumes and the index hierarchy, from the O_0 voxelisation (CPU, once per geometry)."""
    import moderngl

    area0 = np.frombuffer(gv.area.read(), np.float32).reshape(tuple(gv.fine.size[::-1]) + (4,))
    grids = level_grids(grid, levels)
    blocking = [gv.blocking]
    for g, b in zip(grids[1:], level_blocking(area0, grids)[1:]):
        blocking.append(ctx.texture3d(tuple(n + 1 for n in g.size), 4, np.ascontiguousarray(b).tobytes(), dtype="f4"))
    index = index_hierarchy(area0, grids)
    index_textures = [ctx.texture3d(tuple(int(c) for c in g.size), 1, I.astype(np.float32).tobytes(), dtype="f4")
                      for g, I in zip(grids, index)]
    for t in blocking[1:] + index_textures:
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return OctreeGeometry(grids, blocking, index_textures, index)


@dataclass
class OctreeState:
    """The light of every level; level 0 is the injected LPV state (owned by the injection pass)."""
    levels: list

    def release(self):
        for s in self.levels[1:]:
            s.release()


def downsample(ctx, programs, state0: LpvGridState, geo: OctreeGeometry) -> OctreeState:
    """§3.2: O_i.injected = Σ of its eight children in O_{i-1}.injected (Eq. 2 for a flux state)."""
    prog = programs.compute("lpv/octree_downsample.glsl")
    levels = [state0]
    for g in geo.grids[1:]:
        src, dst = levels[-1], LpvGridState(ctx, g)
        bind_named(prog, list(zip(("u_src_r", "u_src_g", "u_src_b"), src.injected.textures())))
        bind_images(dst.injected.textures())
        set_uniform(prog, "u_src_size", tuple(int(c) for c in src.grid.size))
        set_uniform(prog, "u_dst_size", tuple(int(c) for c in g.size))
        dispatch(prog, g.size)
        dst.injected_flux = state0.injected_flux
        levels.append(dst)
    return OctreeState(levels)


def propagate_levels(ctx, programs, tree: OctreeState, geo: OctreeGeometry, settings: LpvSettings,
                     per_step=None) -> dict:
    """§3.3: `octree_iterations` propagation steps on every level with its own occlusion, accumulating (A_i).
    `per_step(step)` (diagnostics) is called before step 1 and after each step of all levels; without it each level
    runs its k steps at once."""
    k = settings.octree_iterations
    fixed = replace(settings, max_iterations=k if per_step is None else 1, epsilon=0.0)
    sources = []
    for i, st in enumerate(tree.levels):
        # The injected light itself lights nearby surfaces. It is counted once in its cell, not once per cell it
        # crosses, so it shares the 1/8^i of the downsampling rather than the 1/4^i of the merge: start A_i with
        # J_i/2^i, and M = A_i/4^i holds J_i/8^i + Σ steps/4^i (lpv/octree_merge.glsl; Ô_i = O_i before step 1).
        if i == 0:
            copy_volumes(ctx, st.injected, st.accum)
        else:
            for a, b in zip(st.injected.textures(), st.accum.textures()):
                b.write((np.frombuffer(a.read(), np.float32) / 2.0 ** i).tobytes())
        sources.append(st.injected)
    if per_step is not None:
        per_step(0)
    for step in range(1 if per_step is None else k):
        for st, blocking, i in zip(tree.levels, geo.blocking, range(len(sources))):
            propagate(ctx, programs, st, sources[i], st.injected_flux, blocking, fixed, accumulate=True)
            if per_step is not None:
                copy_volumes(ctx, st.last, st.injected_next)  # the next step's source (ping/pong are the buffers)
                sources[i] = st.injected_next
        if per_step is not None:
            per_step(step + 1)
    s0 = tree.levels[0]
    hist = np.bincount(flatten_index(geo.index).ravel(), minlength=len(geo.grids))
    return {"cascades": [{"cells": list(s0.grid.size), "cell": s0.grid.cell, "injected_flux": s0.injected_flux,
                          "bounces": [{"injected_flux": s0.injected_flux, "iterations": k * len(tree.levels)}],
                          "iterations": k * len(tree.levels)}],
            "octree": {"levels": len(tree.levels), "iterations_per_level": k,
                       "level_cells": [list(g.size) for g in geo.grids],
                       "index_cells": [int(c) for c in hist]}}


@dataclass
class MergedState:
    """M (§3.4): an O_0-sized accumulated volume, read by lpv/lighting.py like a cascade's state; `index` is I(x)."""
    grid: Grid
    accum: Volumes
    index: object

    def release(self):
        self.accum.release()
        self.index.release()


def merge(ctx, programs, tree: OctreeState, geo: OctreeGeometry) -> MergedState:
    """§3.4: M(x) = S(x) (Eq. 1) of the accumulated volumes, in O_0 units (lpv/octree_merge.glsl)."""
    grid = tree.levels[0].grid
    merged = MergedState(grid, make_volumes(ctx, grid), ctx.texture3d(tuple(grid.size), 1, dtype="f4"))
    prog = programs.compute("lpv/octree_merge.glsl")
    l = len(tree.levels)
    unit = 0
    for name, texs in (("u_level_r", [s.accum.r for s in tree.levels]), ("u_level_g", [s.accum.g for s in tree.levels]),
                       ("u_level_b", [s.accum.b for s in tree.levels]), ("u_index", geo.index_textures)):
        unit = bind_samplers(prog, name, texs, unit, pad_to=MAX_LEVELS)
    for unit, tex in enumerate(merged.accum.textures()):
        tex.bind_to_image(unit, read=False, write=True)
    merged.index.bind_to_image(3, read=False, write=True)
    set_uniform(prog, "u_levels", l)
    set_uniform(prog, "u_grid_size", tuple(int(c) for c in grid.size))
    dispatch(prog, grid.size)
    return merged


def lookup_settings(settings: LpvSettings) -> LpvSettings:
    """The lighting step's settings for M: Kaplanyan's intensity lookup (see the module docstring)."""
    return replace(settings, lookup="intensity")


def read_volumes(vol: Volumes, grid: Grid) -> np.ndarray:
    """(nz, ny, nx, 3, 4) float64 SH coefficients of a volume."""
    return np.stack([np.frombuffer(t.read(), np.float32).reshape(grid.shape_zyx + (4,)) for t in vol.textures()],
                    axis=-2).astype(np.float64)


def level_fluxes(tree: OctreeState, which: str = "injected") -> list[float]:
    """Σ c0·2√π per level (RGB summed): the flux each level holds."""
    return [float(read_volumes(getattr(s, which), s.grid)[..., 0].sum() * SH_FLUX) for s in tree.levels]


def octree_errors(tree: OctreeState) -> tuple[float, float]:
    """Olovsson and Doggett 2013, §4.1: e_abs, e_rel = mean over the elements of O_1..O_{l-1} of ‖O_i − Ô_i‖∞
    (and / ‖O_i‖∞), Ô_i the downsampling of O_{i-1}. Compared: the accumulated volumes in merge units (A_i/4^i,
    which the paper's "uniform range" means), Ô_i = the mean of the eight children (empty children outside an odd
    level count as 0). ‖·‖∞ over the 12 coefficients (RGB × 4) as absolute values. e_rel skips (and does not count)
    elements with ‖O_i‖∞ below 1e-4 of the level's largest (light not yet arrived: float32 crumbs there give
    ratios of 10⁴ and more, meaningless)."""
    vols = [read_volumes(s.accum, s.grid) / 4.0 ** i for i, s in enumerate(tree.levels)]
    e_abs, e_rel, count, lit_count = 0.0, 0.0, 0, 0
    for i in range(1, len(vols)):
        shape = vols[i].shape[:3]
        child = vols[i - 1].reshape(vols[i - 1].shape[:3] + (12,))
        hat = pool(child, 2, shape, 0) / 8.0
        o = vols[i].reshape(shape + (12,))
        diff = np.abs(o - hat).max(axis=-1)
        norm = np.abs(o).max(axis=-1)
        lit = norm > 1e-4 * norm.max() if norm.size else norm
        e_abs += float(diff.sum())
        e_rel += float((diff[lit] / norm[lit]).sum())
        count += diff.size
        lit_count += int(lit.sum())
    return e_abs / max(count, 1), e_rel / max(lit_count, 1)
