"""LPV building blocks: constants, SH helpers, settings, the per-cascade GPU state, fixed-point resolve.

Shared by lpv.py (injection, propagation, lighting) and lpv_occlusion.py (geometry volume, absorbed light).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import direct
from .gpu_context import zero_texture
from .grid import Grid

FAR_FACE = 0.4006696846  # solid angle of the far face of the next cell, seen from a cell centre (design.md §3)
SIDE_FACE = 0.4234313544  # each of its four side faces; FAR_FACE + 4·SIDE_FACE = 2π/3
AXES = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))
FIXED_RANGE = 2.0 ** 29  # fixed-point headroom: a cell's coefficient sum stays below 2³¹ (see flux_bound)
SH_FLUX = 2.0 * math.sqrt(math.pi)  # flux of SH coefficients c: c0·2√π



@dataclass(frozen=True)
class LpvSettings:
    resolution: int = 32  # cells along the longest axis of the (finest) grid
    cascades: int = 1  # nested grids, each twice the extent of the last
    rsm_resolution: int = 128  # texels per side of each RSM view (sun: twice that)
    rsm_downsample: int = 1  # propagate: inject one VPL per k×k RSM texels, intensity-aware (seed 001); 1, 2, 4
    max_iterations: int = 64
    epsilon: float = 1e-3  # stop when one step moved less than this fraction of the injected flux
    occlusion: bool = True  # fuzzy occlusion from the geometry volume
    clamp_negative: bool = False
    damping: bool = False  # seed 000's directional-derivative damping at lookup
    blend_cells: float = 2.0  # cascade border blend width (cells)
    bounces: int = 8  # indirect bounces (1 = light reflected once; Cycles' default 8); > 1 need occlusion
    # Gathered transport: gather this many bounces, extrapolate the rest to `bounces` as a geometric series of the
    # last pass (lpv_tail.glsl); 0 = gather every bounce. The propagating transport propagates every bounce.
    gathered_bounces: int = 4
    lookup: str = "flux"  # "flux": absorbed face flux per area (conserves energy); "intensity": Kaplanyan's I/cell²
    # Octree LPV (seed 002, lpv_octree.py): 0 = uniform grid; L ≥ 1 = full octree O_0..O_{L-1} (O_0 = this grid,
    # O_i = n/2^i), index volume, per-level propagation, merge (L = 1: the octree path with one level, which equals
    # the uniform grid with `octree_iterations` steps, one bounce, intensity lookup).
    octree_levels: int = 0
    octree_iterations: int = 4  # propagation steps on every octree level (seed 002 §4: k = 4)
    # Transport: "gather" sends light straight from VPLs to every surface voxel with fuzzy visibility, bounce by
    # bounce (lpv_gather.py: the face scheme turns light sideways within a few cells); "propagate" is the classic
    # LPV. World light propagates either way. The gather writes surface voxels' irradiance, which only the flux
    # lookup with occlusion reads: the intensity lookup, occlusion=False and the octree always propagate (see
    # `gathers`). `gather_vpls` bounds the VPLs per bounce: RSM texels and surface voxels are clustered to fit.
    transport: str = "gather"
    gather_vpls: int = 512

    def __post_init__(self):
        if not 4 <= self.resolution <= 256:
            raise ValueError(f"resolution {self.resolution} out of range 4..256")
        if not 1 <= self.cascades <= 4:
            raise ValueError(f"cascades {self.cascades} out of range 1..4")
        if self.lookup not in ("flux", "intensity"):
            raise ValueError(f"lookup must be 'flux' or 'intensity', not {self.lookup!r}")
        if self.transport not in ("gather", "propagate"):
            raise ValueError(f"transport must be 'gather' or 'propagate', not {self.transport!r}")
        if self.gathered_bounces < 0:
            raise ValueError(f"gathered_bounces {self.gathered_bounces} must be ≥ 0 (0: gather every bounce)")
        if not 16 <= self.gather_vpls <= 65536:
            raise ValueError(f"gather_vpls {self.gather_vpls} out of range 16..65536")
        if self.rsm_downsample not in (1, 2, 4):
            raise ValueError(f"rsm_downsample must be 1, 2 or 4, not {self.rsm_downsample}")
        if self.bounces < 1 or self.max_iterations < 1 or self.rsm_resolution < 8:
            raise ValueError("bounces and max_iterations must be ≥ 1 and rsm_resolution ≥ 8")
        if not 0 <= self.octree_levels <= 5 or self.octree_iterations < 1:
            raise ValueError("octree_levels must be 0..5 and octree_iterations ≥ 1")
        if self.octree_levels and (self.cascades != 1 or not self.occlusion
                                   or 2 ** (self.octree_levels - 1) > self.resolution):
            raise ValueError("the octree LPV needs cascades=1, occlusion (its index volume comes from the geometry "
                             "volume) and 2^(octree_levels-1) ≤ resolution")

    @property
    def gathers(self) -> bool:
        """Whether light is gathered (transport="gather" where the flux lookup reads it)."""
        return (self.transport == "gather" and self.lookup == "flux" and self.occlusion
                and not self.octree_levels)


def sh_basis(d) -> np.ndarray:
    x, y, z = d
    return np.array([0.282094792, -0.488602512 * y, 0.488602512 * z, -0.488602512 * x])


def sh_clamped_cosine(n) -> np.ndarray:
    x, y, z = n
    return np.array([0.886226925, -1.023326708 * y, 1.023326708 * z, -1.023326708 * x])


def transfer_matrices() -> tuple[np.ndarray, np.ndarray]:
    """The face scheme of lpv_propagate.glsl as linear maps, one per neighbour direction d (light travelling d):
    T_d = Σ_faces (lobe(face)/π) ⊗ Y(ω_face)·Δω_face (coefficients received), and the incident-flux row
    Σ_faces Y(ω_face)·Δω_face. Returns (6, 4, 4) and (6, 4) float32."""
    transfer = np.zeros((6, 4, 4))
    incident = np.zeros((6, 4))
    for n, d in enumerate(AXES):
        d = np.asarray(d, float)
        for f in AXES:
            f = np.asarray(f, float)
            if f @ d < -0.5:
                continue  # the face shared with the neighbour
            far = f @ d > 0.5
            w = d if far else (d + 0.5 * f) / np.linalg.norm(d + 0.5 * f)
            weight = sh_basis(w) * (FAR_FACE if far else SIDE_FACE)
            transfer[n] += np.outer(sh_clamped_cosine(f) / math.pi, weight)
            incident[n] += weight
    return transfer.astype(np.float32), incident.astype(np.float32)


@dataclass
class Volumes:
    """Three RGBA32F 3D textures (SH coefficients of red, green, blue) on one grid."""
    r: object
    g: object
    b: object

    def release(self):
        for t in (self.r, self.g, self.b):
            t.release()

    def textures(self):
        return self.r, self.g, self.b


def _volumes(ctx, grid: Grid, data: np.ndarray | None = None) -> Volumes:
    import moderngl

    size = tuple(int(v) for v in grid.size)
    texs = []
    for i in range(3):
        payload = None if data is None else np.ascontiguousarray(data[..., i, :], np.float32).tobytes()
        t = ctx.texture3d(size, 4, payload, dtype="f4")
        t.filter = (moderngl.LINEAR, moderngl.LINEAR)
        t.repeat_x = t.repeat_y = t.repeat_z = False
        texs.append(t)
    if data is None:
        for t in texs:
            zero_texture(ctx, t)
    return Volumes(*texs)


class LpvGridState:
    """GPU state of one cascade: injection accumulator, ping-pong volumes and the accumulation volume."""

    def __init__(self, ctx, grid: Grid):
        self.grid = grid
        n = int(np.prod(grid.size))
        self.accum_ints = ctx.buffer(reserve=n * 12 * 4)
        self.injected = _volumes(ctx, grid)
        self.accum = _volumes(ctx, grid)
        self.ping = _volumes(ctx, grid)
        self.pong = _volumes(ctx, grid)
        self.injected_next = _volumes(ctx, grid)  # a bounce's source (ping/pong are the propagation buffers)
        self.counter = ctx.buffer(reserve=4)
        self.face_flux = ctx.buffer(reserve=n * 6 * 16)  # vec4 per cell and direction of travel
        self.front = self.back = None  # absorbed-light irradiance per fine voxel, last pass (set by `absorb`)
        self.front_total = self.back_total = None  # summed over bounces
        self.vpls = None  # the RSM's VPLs for the gathered transport (lpv_gather.vpl_list)

    def release(self):
        for obj in (self.accum_ints, self.injected, self.accum, self.ping, self.pong, self.injected_next,
                    self.counter, self.face_flux,
                    self.front, self.back, self.front_total, self.back_total, self.vpls):
            if obj is not None:
                obj.release()


def _grid_uniforms(prog, grid: Grid) -> None:
    direct._set(prog, "u_grid_origin", tuple(float(c) for c in grid.origin))
    direct._set(prog, "u_grid_cell", float(grid.cell))
    direct._set(prog, "u_grid_size", tuple(int(c) for c in grid.size))


def resolve(ctx, programs, state: LpvGridState, scale: float, target: Volumes, add: bool = False) -> float:
    """Fixed-point sums → float volumes; returns the flux they hold (sum over RGB of |band 0|·2√π)."""
    prog = programs.compute("lpv_resolve.glsl", {"MODE_ADD": 1} if add else None)
    state.accum_ints.bind_to_storage_buffer(4)
    for unit, tex in enumerate(target.textures()):
        tex.bind_to_image(unit, read=True, write=True)
    direct._set(prog, "u_grid_size", tuple(int(c) for c in state.grid.size))
    direct._set(prog, "u_fixed_scale", float(scale))
    nx, ny, nz = state.grid.size
    prog.run((nx + 3) // 4, (ny + 3) // 4, (nz + 3) // 4)
    ints = np.frombuffer(state.accum_ints.read(), np.int32).reshape(-1, 3, 4)
    return float(np.abs(ints[:, :, 0].astype(np.float64)).sum() / scale * SH_FLUX)


def copy_volumes(ctx, src: Volumes, dst: Volumes) -> None:
    for a, b in zip(src.textures(), dst.textures()):
        b.write(a.read())


