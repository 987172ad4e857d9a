# SPDX-License-Identifier: GPL-3.0-or-later
"""Surface voxelisation on the GPU (Freed 2018, §4.1): area, albedo·opacity, normal and emission per voxel.

Two methods, as compared in Freed 2018, §5.2.2 / Table 5.2:
  * ``mode="raster"`` (§4.1.1, after Crassin and Green 2012): dominant-axis projection in a geometry shader,
    conservative coverage by triangle dilation (or the pixel bounding box for slivers), and an *exact* area per
    voxel: each fragment clips the original triangle to its pixel and to every voxel slab it crosses in depth
    (voxel/raster.glsl).
  * ``mode="tessellation"`` (§4.1.2, after Fei et al. 2012): the tessellator cuts each triangle into sub-triangles
    smaller than 1/supersample voxel; a geometry shader deposits each at its centroid, with its exact area.
    Triangles needing a level above GL_MAX_TESS_GEN_LEVEL are split on the CPU first (voxel/tessellate.py).

With ``sides=True`` (raster only) the albedo is kept per side of each voxel, covered surfaces left out of the side
they are hidden from (voxel/raster.glsl): `VoxelVolumes.albedo_back` holds the back side's.

Averages are race-free and deterministic: every quantity is summed with integer ``imageAtomicAdd`` in fixed
point (1 unit = 2^-scale_bits cell², default 2^-24: a voxel holds up to 256 cell² of surface; the shader flags a
wrapped sum and `voxelize` re-runs with fewer bits), then a compute pass divides (voxel/resolve.glsl).

Everything here runs on the GL thread that owns `ctx` (gl/context.GpuWorker), including `VoxelVolumes.read`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from ..direct.geometry import POSITION_ONLY, POSITION_UV, bind_material
from ..gl.bind import bind_named, dispatch, set_uniform, set_uniforms, zero_texture
from ..scene import Scene
from .tessellate import draw_tessellated, patch_buffers

MODES = ("raster", "tessellation")
DEFAULT_SCALE_BITS = 24      # fixed point: 2^-24 cell² per unit, 2^8 = 256 cell² of surface per voxel before wrap
DILATION_PX = 0.5 + 1.0 / 64.0   # half a pixel, plus slack for the rasteriser's 1/256-pixel vertex snapping
VOLUME_NAMES = ("area", "albedo", "normal", "emission")
SIDES_BYTES = 256 * 2 ** 20  # the front-most image's budget for sides=True; larger grids keep one albedo


@dataclass
class VoxelVolumes:
    """RGBA32F 3D textures of size grid.size (x, y, z); see voxel/resolve.glsl for the channels.

    area: rgb = projected area onto the x/y/z planes (m²), a = surface area (m²);
    albedo: rgb = area-weighted mean albedo (voxel_albedo: diffuse and glossy reflectance), a = opacity = min(1, max projected area / cell²);
    normal: xyz = area-weighted mean sign-canonicalised geometric normal (not renormalised), w = 0;
    emission: rgb = area-weighted mean emitted radiance;
    albedo_back (sides=True): rgb = the back side's mean albedo (the side opposite the mean normal), albedo's rgb
    then the front side's; None where not asked for or over SIDES_BYTES (one albedo serves both sides).
    A caller that reads no albedo or emission may release those and leave None (vct/volumes.voxelize_scene).
    """
    grid: Grid
    area: object
    albedo: object
    normal: object
    emission: object
    mode: str
    supersample: int
    scale_bits: int          # fixed-point bits actually used
    reruns: int = 0          # re-runs after a fixed-point overflow (0 normally)
    albedo_back: object = None
    front: object = None     # sides=True, keep_front=True: the front-most image, the caller's to release or reuse
    position: object = None  # positions=True: rgb the surfaces' area-weighted centroid, cells from the voxel's corner
    # (it and the extents 0 where a voxel is empty, like every volume)
    extent_lo: object = None  # positions=True: rgb the box the surfaces span, likewise
    extent_hi: object = None

    def textures(self) -> dict:
        names = VOLUME_NAMES + ("albedo_back", "position", "extent_lo", "extent_hi")
        return {name: getattr(self, name) for name in names if getattr(self, name) is not None}

    def read(self, names=None) -> dict:
        """{name: (nz, ny, nx, 4) float32} of every volume, or of those in `names` that exist — call on the GL
        thread (e.g. inside ``Engine().worker.call``)."""
        nx, ny, nz = self.grid.size
        return {name: np.frombuffer(tex.read(), np.float32).reshape(nz, ny, nx, 4).copy()
                for name, tex in self.textures().items() if names is None or name in names}

    def occupancy(self) -> np.ndarray:
        """(nz, ny, nx) bool: voxels with surface area > 0 (GL thread)."""
        nx, ny, nz = self.grid.size
        return np.frombuffer(self.area.read(), np.float32).reshape(nz, ny, nx, 4)[..., 3] > 0.0

    def release(self) -> None:
        for tex in self.textures().values():
            tex.release()


def voxelize(ctx, programs, scene: Scene, geometry, textures, grid: Grid, mode: str = "raster",
             supersample: int = 2, scale_bits: int = DEFAULT_SCALE_BITS, sides: bool = False, front=None,
             keep_front: bool = False, axis_only: int = -1, positions: bool = False,
             albedo_override: dict | None = None, region: tuple | None = None) -> VoxelVolumes:
    """Voxelise the scene's surfaces into `grid` (GL thread); returns new textures the caller releases.

    `geometry`: direct/geometry.GeometryBuffers of `scene` (raster draws its VBO; tessellation uploads its own patch
    buffer with oversized triangles split, so only the material ranges are read). `textures`: the MaterialTextures of
    direct/geometry.upload_textures. `supersample`: raster — pixels per voxel edge, i.e. texture samples per voxel face
    (areas are exact at any value); tessellation — sub-triangles per voxel edge. `scale_bits`: fixed-point
    fraction bits (1 unit = 2^-bits cell²); lowered automatically, and reported, if a voxel's sum would wrap.
    `sides`: keep the albedo per side, covered surfaces left out of the side they are hidden from (raster only);
    the front-most image this needs depends on the geometry alone: `keep_front` hands it over in the result's
    `front`, and `front` takes one back (same geometry, grid and supersample) instead of rasterising it again.
    `axis_only` (raster only) ≥ 0 voxelises only the triangles whose dominant axis it is (x, y, z: 0, 1, 2) — the
    LPV's receivers, one per voxel and axis (lpv/occlusion.py) — and −1 all of them. The front-most image is per
    dominant axis, so one made of every triangle serves each axis. `positions` (raster only) adds the surfaces'
    area-weighted centroid and box per voxel (VoxelVolumes.position, extent_lo, extent_hi).
    `albedo_override` (raster only), {material index: rgb}: those materials' surfaces get that constant albedo and
    every other surface none — the areas stay, so a one-hot colour gives each voxel side the share of its seen area
    a material covers (lpv/receivers.material_weights).
    `region` (raster only), voxels (lo, hi) of `grid`: only those, into volumes of that part (region_grid), each
    voxel as the whole grid's voxelisation gives it, byte for byte (lpv/regional.py); the rasteriser draws their
    pixels only (region_scissor). A `front` must then come from the same region or the whole grid."""
    _check_grid(ctx, grid, mode, supersample)
    if (axis_only >= 0 or positions or albedo_override is not None or region is not None) and mode != "raster":
        raise ValueError("axis_only, positions, albedo_override and region need mode='raster'")
    supersample = int(supersample)
    albedo_max, emission_max = _maxima(scene, geometry, textures, albedo_override)
    sides = bool(sides) and mode == "raster" and _sides_fit(ctx, grid, supersample)
    positions = bool(positions)
    part, scissor, region_uniforms = _region_setup(grid, region, supersample, axis_only)
    accs, flags = _accumulators(ctx, part, sides, positions)
    patches = patch_buffers(ctx, scene, grid, supersample) if mode == "tessellation" else None
    own_front = sides and front is None
    fronts = ([front] if front is not None else _front_most(ctx, programs, scene, geometry, textures, grid,
                                                             supersample, region)) if sides else []
    # image units of voxel/common.glsl: 0–3 accumulators, 4 flags, 5 albedo_back, 6 front-most, 7 positions
    images = list(zip([0, 1, 2, 3] + [5] * sides + [7] * positions + [4] + [6] * len(fronts), accs + [flags] + fronts))
    defines = {**({"SIDES": None} if sides else {}), **({"POSITIONS": None} if positions else {})}
    uniforms = {"u_grid_origin": grid.origin, "u_inv_cell": 1.0 / grid.cell, "u_grid_size": grid.size,
                "u_supersample": float(supersample), "u_albedo_max": albedo_max, "u_emission_max": emission_max,
                "u_axis_only": int(axis_only), **region_uniforms}
    try:
        reruns = 0
        while _deposit(ctx, programs, scene, (geometry, patches), textures, grid, supersample,
                       {**uniforms, "u_fixed_scale": float(2.0 ** scale_bits)}, images, defines,
                       albedo_override, scissor) and scale_bits > 0:
            scale_bits = _smaller_scale(scene, grid, scale_bits, reruns)
            reruns += 1
        volumes = _resolve(ctx, programs, accs, part, scale_bits, albedo_max, emission_max, sides, positions)
    finally:
        for t in accs + [flags] + (fronts if own_front and not keep_front else []):
            t.release()
        if patches is not None:
            patches[0].release()
    return VoxelVolumes(part, *volumes[:4], mode=mode, supersample=supersample, scale_bits=scale_bits,
                        reruns=reruns, albedo_back=volumes[4] if sides else None,
                        front=fronts[0] if own_front and keep_front else None,
                        **dict(zip(("position", "extent_lo", "extent_hi"), volumes[-3:] if positions else ())))


def region_grid(grid: Grid, region: tuple) -> Grid:
    """The part (lo, hi) of `grid`, voxels lo … hi − 1, as a grid of its own (the volumes of a region's
    voxelisation)."""
    lo, hi = (np.asarray(c, np.int64) for c in region)
    if np.any(lo < 0) or np.any(hi > np.asarray(grid.size)) or np.any(hi <= lo):
        raise ValueError(f"region {lo.tolist()}..{hi.tolist()} is not a part of grid {grid.size}")
    return Grid(tuple(np.asarray(grid.origin) + lo * grid.cell), grid.cell, tuple(int(n) for n in hi - lo))


def _region_setup(grid: Grid, region, supersample: int, axis_only: int) -> tuple:
    """The volumes' grid, the raster's scissor and voxel/common.glsl's region uniforms of a voxelisation of `region`
    (None: the whole grid)."""
    if region is None:
        return grid, None, {"u_region_lo": (0, 0, 0), "u_region_size": grid.size}
    part = region_grid(grid, region)
    return part, region_scissor(region, supersample, axis_only), {
        "u_region_lo": tuple(int(c) for c in region[0]), "u_region_size": part.size}


# The dominant-axis projection's pixel axes (u, v) per axis (voxel/raster.glsl to_plane: x → (y, z), y → (z, x)).
PLANE_AXES = ((1, 2), (2, 0), (0, 1))


def region_scissor(region: tuple, supersample: int, axis_only: int = -1) -> tuple:
    """The raster's scissor (x, y, w, h) holding every pixel of the region's voxel columns in the projection along
    `axis_only` (the union over the three axes for −1): pixels outside it could only deposit outside the region."""
    lo, hi = (np.asarray(c, np.int64) for c in region)
    axes = [PLANE_AXES[axis_only]] if axis_only >= 0 else PLANE_AXES
    u0, v0 = min(lo[u] for u, _ in axes), min(lo[v] for _, v in axes)
    u1, v1 = max(hi[u] for u, _ in axes), max(hi[v] for _, v in axes)
    ss = int(supersample)
    return int(u0 * ss), int(v0 * ss), int((u1 - u0) * ss), int((v1 - v0) * ss)


def _maxima(scene, geometry, textures, albedo_override) -> tuple[float, float]:
    """The fixed-point ranges of the albedo and emission sums: the materials' maxima, the override's albedo."""
    used = sorted({m for m, _, _ in geometry.ranges})
    albedo_max, emission_max = material_maxima(scene, used, textures.transport)
    if albedo_override is not None:
        albedo_max = max([float(max(c)) for c in albedo_override.values()] + [0.0]) or 1.0
    return albedo_max, emission_max


def _accumulators(ctx, grid: Grid, sides: bool, positions: bool) -> tuple[list, object]:
    """The integer accumulators voxel/common.glsl adds into (4, + albedo_back, + acc_position) and the flags."""
    import moderngl

    nx, ny, nz = grid.size
    accs = [ctx.texture3d((4 * nx, ny, nz), 1, dtype="u4") for _ in range(4 + sides)]
    accs += [ctx.texture3d((4 * nx, 3 * ny, nz), 1, dtype="u4")] * positions
    flags = ctx.texture3d((1, 1, 1), 1, np.zeros(1, np.uint32).tobytes(), dtype="u4")
    for t in accs + [flags]:
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return accs, flags


def _deposit(ctx, programs, scene, buffers, textures, grid, supersample, uniforms, images, defines,
             albedo_override=None, scissor=None) -> bool:
    """One voxelisation pass into the accumulators, zeroed first (`images`: (unit, texture) of voxel/common.glsl,
    the flags at unit 4 and the front-most image, read only, at 6), drawn from `buffers` = (geometry, tessellation
    patches or None); True where a voxel's area sum wrapped."""
    geometry, patches = buffers
    for unit, t in images:
        if unit not in (4, 6):  # a copy from a zero buffer (gl/bind.zero_texture): faster than a compute pass
            zero_texture(ctx, t)
    ctx.memory_barrier()
    flags = dict(images)[4]
    flags.write(np.zeros(1, np.uint32).tobytes())
    for unit, t in images:
        t.bind_to_image(unit, read=True, write=True)
    if patches is None:
        _draw_raster(ctx, programs, scene, geometry, textures, grid, supersample, uniforms, defines or None,
                     albedo_override, scissor)
    else:
        draw_tessellated(ctx, programs, scene, patches, textures, uniforms)
    ctx.memory_barrier()
    return bool(np.frombuffer(flags.read(), np.uint32)[0])


def _sides_fit(ctx, grid: Grid, supersample: int) -> bool:
    """Whether sides=True's front-most image fits SIDES_BYTES and the 3D texture size limit."""
    return front_bytes(grid, supersample) <= SIDES_BYTES and \
        2 * sum(grid.size) <= int(ctx.info.get("GL_MAX_3D_TEXTURE_SIZE", 2048))


def front_bytes(grid: Grid, supersample: int) -> int:
    """Bytes of the front-most image of sides=True: (side, side, 2·(nx + ny + nz)) uints, side = the raster's."""
    side = int(max(grid.size)) * int(supersample)
    return side * side * 2 * int(sum(grid.size)) * 4


def _front_most(ctx, programs, scene, geometry, textures, grid, supersample, region=None) -> list:
    """The MODE_FRONT pass of voxel/raster.glsl: an r32ui image of the front-most depth per pixel column, voxel
    layer and side, the three axes' layers one after the other (a list of it; the caller releases it). With a
    `region`, right in the region's columns only."""
    import moderngl

    side = int(max(grid.size)) * int(supersample)
    front = ctx.texture3d((side, side, 2 * int(sum(grid.size))), 1, dtype="u4")
    front.filter = (moderngl.NEAREST, moderngl.NEAREST)
    zero_texture(ctx, front)
    front.bind_to_image(6, read=True, write=True)
    uniforms = {"u_grid_origin": grid.origin, "u_inv_cell": 1.0 / grid.cell, "u_grid_size": grid.size,
                "u_supersample": float(supersample)}
    # A region: each axis's triangles behind that axis's scissor (the union of the three covers most of the image)
    for axis in (-1,) if region is None else range(3):
        _draw_raster(ctx, programs, scene, geometry, textures, grid, supersample, {**uniforms, "u_axis_only": axis},
                     {"MODE_FRONT": None}, scissor=None if region is None else region_scissor(region, supersample, axis))
    ctx.memory_barrier()
    return [front]


def _check_grid(ctx, grid: Grid, mode: str, supersample) -> None:
    """ValueError for a mode, supersampling or grid this context cannot voxelise."""
    if mode not in MODES:
        raise ValueError(f"unknown voxelisation mode {mode!r} (choose from {', '.join(MODES)})")
    if int(supersample) < 1:
        raise ValueError("supersample must be ≥ 1")
    nx, ny, nz = grid.size
    max_3d = int(ctx.info.get("GL_MAX_3D_TEXTURE_SIZE", 2048))
    if 4 * nx > max_3d or ny > max_3d or nz > max_3d:
        raise ValueError(f"grid {grid.size} too large: accumulators need 4·nx, ny, nz ≤ {max_3d}")
    if mode == "raster" and max(grid.size) * int(supersample) > 16384:
        raise ValueError(f"grid {grid.size} × supersample {int(supersample)} exceeds 16384 pixels")


def _smaller_scale(scene: Scene, grid: Grid, scale_bits: int, reruns: int) -> int:
    """A voxel's area sum wrapped: the fixed-point fraction bits to retry with — room for the whole scene's area in
    one voxel on the first retry, then two bits fewer each time."""
    total_cells = float(scene_area(scene)) / grid.cell ** 2
    safe = int(np.floor(np.log2(2.0 ** 31 / max(total_cells, 1e-30))))
    return max(0, min(scale_bits - 1, safe) if reruns == 0 else scale_bits - 2)


def scene_area(scene: Scene) -> float:
    """Total triangle area of the scene (m², float64)."""
    p = np.asarray(scene.positions, np.float64)
    c = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return float(0.5 * np.sqrt(np.einsum("ij,ij->i", c, c)).sum())


def material_maxima(scene: Scene, used, transport: np.ndarray) -> tuple[float, float]:
    """Largest voxel albedo (voxel/common.glsl voxel_albedo) and emission component over the materials in `used`
    (fixed-point normalisers); `transport`: the materials' albedo terms (direct/geometry.MaterialTextures)."""
    albedo, emission = 0.0, 0.0
    for i in used:
        mat = scene.materials[i] if 0 <= i < len(scene.materials) else None
        if mat is None:
            albedo = max(albedo, 0.8)
            continue
        if 0 <= mat.base_color_texture < len(scene.textures):
            color = float(np.max(scene.textures[mat.base_color_texture].pixels[..., :3], initial=0.0))
        else:
            color = max(float(c) for c in mat.base_color[:3])
        scale, offset = transport[i]
        albedo = max(albedo, float(np.max(max(color, 0.0) * scale + offset)))
        emission = max(emission, max(float(c) for c in mat.emission[:3]))
    return (albedo if albedo > 0 else 1.0), (emission if emission > 0 else 0.0)


def _draw_raster(ctx, programs, scene, geometry, textures, grid, supersample, uniforms, defines=None,
                 albedo_override=None, scissor=None) -> None:
    import moderngl

    prog = programs.raster("voxel/raster.glsl", defines)
    side = max(grid.size) * supersample
    set_uniforms(prog, {**uniforms, "u_viewport": (float(side), float(side)), "u_dilation": DILATION_PX,
                        "u_supersample_i": supersample})
    fbo = ctx.empty_framebuffer((side, side))
    layout = (geometry.vbo, POSITION_UV, "in_position", "in_uv") if "in_uv" in prog else \
        (geometry.vbo, POSITION_ONLY, "in_position")  # MODE_FRONT samples no texture
    vao = ctx.vertex_array(prog, [layout])
    try:
        fbo.use()
        fbo.viewport = (0, 0, side, side)
        ctx.scissor = scissor  # None: every pixel
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        for mat_index, first, count in geometry.ranges:
            bind_material(prog, scene, mat_index, textures)
            if albedo_override is not None:
                _override_albedo(prog, albedo_override.get(mat_index, (0.0, 0.0, 0.0)))
            vao.render(moderngl.TRIANGLES, vertices=count, first=first)
    finally:
        ctx.scissor = None
        vao.release()
        fbo.release()


def _override_albedo(prog, rgb) -> None:
    """voxel/common.glsl voxel_albedo returns `rgb` for the material just bound."""
    set_uniform(prog, "u_base_color", tuple(float(c) for c in rgb))
    set_uniform(prog, "u_albedo_scale", (1.0, 1.0, 1.0))
    set_uniform(prog, "u_albedo_offset", (0.0, 0.0, 0.0))
    set_uniform(prog, "u_use_texture", False)


def _resolve(ctx, programs, accs, grid, scale_bits, albedo_max, emission_max, sides, positions) -> list:
    """The volumes of VOLUME_NAMES, then albedo_back (`sides`), then position (`positions`), from `accs` in that
    order."""
    defines = {"MODE_RESOLVE": None, **({"SIDES": None} if sides else {}), **({"POSITIONS": None} if positions else {})}
    prog = programs.compute("voxel/resolve.glsl", defines)
    nx, ny, nz = grid.size
    out = [ctx.texture3d((nx, ny, nz), 4, dtype="f4") for _ in range(len(VOLUME_NAMES) + sides + 3 * positions)]
    for t in out:  # the resolve stores to occupied voxels only
        zero_texture(ctx, t)
    names = ["u_acc_area", "u_acc_albedo", "u_acc_normal", "u_acc_emission"] + ["u_acc_albedo_back"] * sides + \
        ["u_acc_position"] * positions
    bind_named(prog, list(zip(names, accs)))
    for unit, t in zip([0, 1, 2, 3] + [4] * sides + [5, 6, 7] * positions, out):  # voxel/resolve.glsl's bindings
        t.bind_to_image(unit, read=False, write=True)
    cell_area = grid.cell ** 2
    set_uniforms(prog, {"u_grid_size": grid.size, "u_unit_area": cell_area / 2.0 ** scale_bits, "u_cell_area": cell_area,
                        "u_albedo_max": albedo_max, "u_emission_max": emission_max})
    dispatch(prog, (nx, ny, nz))
    ctx.memory_barrier()
    return out
