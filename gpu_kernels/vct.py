"""Voxel Cone Tracing (seed 004; Crassin et al. 2011): voxelize → inject direct light → mipmap → bounce → trace.

Passes (pipeline.py wires them into the pass cache):
  vct_voxelize  the shared GPU voxelizer (voxelize.py) on a grid padded so every mip level nests exactly;
  vct_inject    surface points rasterised along their dominant axis and lit by every light exactly as the Diffuse
                Direct pass lights pixels (direct_eval.glsl), averaged into six faces per voxel: the radiance
                leaving through each face, its coverage and where its surfaces lie (vct_inject*.glsl);
  vct_mipmap    the filtered radiance volumes: isotropic (mean of children) or anisotropic (six directions,
                composited front to back, plus where each texel's surfaces lie along each axis, so a cone skips
                surfaces behind where it started) (vct_mipmap.glsl, seed 004 §4.4);
  vct_bounce    bounces − 1 gathers at the voxel faces, each followed by a re-mip (vct_bounce.glsl);
  vct_trace     diffuse cones per G-buffer pixel (or per s × s block, indirect_scale) → Diffuse Indirect and voxel
                AO (vct_trace.glsl, seed 004 §4.5.2); with anisotropic volumes each cone is a bundle of sub-rays
                that meet surfaces where they cross them (vct_crossing.glsl);
  vct_upsample  reduced-resolution results back to every pixel, depth- and normal-aware (vct_upsample.py, seed 003);
  vct_accumulate  temporal average of jittered cone sets (vct_temporal.py);
  vct_specular  one glossy cone per pixel → Glossy Indirect (vct_specular.py).

Every scale is derived; the shaders' comments give the derivations (self-occlusion bound, step opacity, anisotropic
optical depth, the layer test, sub-rays), `cone_table` and `subray_radius` give the cones'. Sky light: the world
colour fills what is left of every cone that leaves the grid; it lands in Diffuse Indirect here, whereas Cycles
counts world light as Diffuse Direct.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from . import direct
from .grid import Grid
from .scene import Scene

MAX_CONES = 32  # vct_common.glsl (cone_table makes at most 31)
MAX_SUBRAYS = 7  # vct_crossing.glsl keeps them in registers (a define per count)
CONE_FIELDS = ("diffuse_cones", "diffuse_aperture", "max_distance", "step_multiplier", "start_offset")


@dataclass(frozen=True)
class VctSettings:
    resolution: int = 64  # voxels along the longest axis of the scene (other axes padded, see vct_grid)
    # A cap around the normal and one ring (5..9) or two rings (13, 16, … 31), cone_table. Default 9 with 7 sub-rays
    # each (anisotropic volumes, vct_crossing.glsl), measured (64³, defaults otherwise, 160×120, against 2048-spp
    # 8-bounce Cycles; Diffuse Indirect / Combined rel-L1, trace time 320×240 Cornell on llvmpipe):
    #   9 cones × 7 sub-rays: Cornell 0.093 / 0.050, spot room 0.059 / 0.022, courtyard 0.080 / 0.059, 12 s;
    #   9 × 5: 0.101 / 0.054, 0.062 / 0.023, 0.087 / 0.064, 7.5 s;  19 × 5: 0.080 / 0.045, 0.057 / 0.022, 0.072 /
    #   0.053, 17 s;  19 × 7: 0.074 / 0.043, 0.058 / 0.022, 0.070 / 0.052, 25 s;  13 × 7: 0.093 / 0.051, 0.064 /
    #   0.024, 0.077 / 0.057.
    # (Before sub-rays, with the volumetric march: 19 cones 0.137 / 0.070, 0.131 / 0.048, 0.178 / 0.125, 2.3 s.)
    diffuse_cones: int = 9
    # Rays per diffuse cone in the per-pixel trace with anisotropic volumes (vct_crossing.glsl): the axis and
    # subrays − 1 around it; each meets surfaces where it crosses them. 1 = the axis only (9 cones: 0.202 / 0.102,
    # 0.099 / 0.036, 0.234 / 0.163). The trace's cost grows about linearly with it.
    subrays: int = 7
    # Cones per voxel face in the bounce gathers (vct_bounce); 0 = diffuse_cones. Bounced light is smooth, and
    # these gathers are most of a multi-bounce frame's time. Default 6, measured against 9 (64³, defaults otherwise,
    # Combined rel-L1 / bounce pass on llvmpipe): Cornell 0.092 vs 0.093 / 3.6 s vs 4.9 s, spot room 0.053 vs
    # 0.058, courtyard 0.180 vs 0.181; 5 cones: 0.095 / 3.2 s, 0.058, 0.169.
    bounce_cones: int = 6
    diffuse_aperture: float = 0.0  # cone half-angle (degrees); 0 = derived: a cone of the region's solid angle
    max_distance: float = 0.0  # metres a cone travels; 0 = until it leaves the grid (or is fully occluded)
    # Indirect bounces in Diffuse Indirect (1 = light reflected once; Cycles' "1 bounce"). Default 8 like Cycles'
    # default: with 1 bounce the interiors came out 0.48 (Cornell) / 0.73 (spot room) Diffuse Indirect rel-L1,
    # most of it light missing.
    bounces: int = 8
    # Gather only this many bounces and extrapolate the rest up to `bounces` as a geometric series of the last
    # increment (vct_cones._extrapolate_tail); 0 = gather every bounce. Each gathered bounce is a full cone pass
    # over the voxels, the tail a few array operations. Default 4, measured against gathering all 8 (Combined
    # rel-L1, 64³, 9 cones everywhere): Cornell 0.093 vs 0.092, spot room 0.058 vs 0.056, courtyard 0.181 vs 0.180
    # in half the time (Cornell bounce pass 4.8 s vs 11.0 s on llvmpipe); gathering 3 was 0.098 / 0.057 / 0.198.
    gathered_bounces: int = 4
    # Step / sampled voxel size of the volumetric march (seed 004 listing 4.1 steps by the cone radius): the bounce
    # gathers, the specular cone, isotropic volumes. The per-pixel sub-rays step one texel (vct_crossing.glsl).
    step_multiplier: float = 0.5
    start_offset: float = 1.5  # voxels along the normal (× ‖n‖₁): the trilinear support of the own texel
    # One glossy cone per pixel along the reflected view direction → Glossy Indirect (vct_specular.py); pixels
    # with no glossy closure or rougher than roughness_cutoff run no cone, so scenes without glossy materials pay
    # one texture fetch per pixel.
    specular_cone: bool = True
    roughness_cutoff: float = 0.5  # specular cone skipped above this Principled roughness (Glossy Indirect = 0)
    # Diffuse cones traced at (width/s) × (height/s) and brought back to full resolution by a depth- and
    # normal-aware upsampling (seed 003, inferred lighting; vct_upsample.py). 1 = every pixel.
    indirect_scale: int = 1
    # Temporal accumulation (vct_temporal.py): each render turns the diffuse cone set about the normal by another
    # angle and averages into a history, until this many frames are in; any change to the trace's inputs restarts
    # it. 0 or 1 = off.
    temporal_frames: int = 0
    cone_rotation: float = 0.0  # degrees the diffuse cone set is turned about the normal (the jitter adds to it)
    # Six directional volumes (Crassin) rather than one isotropic volume. Default on, measured: isotropic voxels
    # show a wall's lit side from both sides, and with 4 bounces Cornell / courtyard Diffuse Indirect came out
    # 1.8× / 5.1× as bright as 8-bounce Cycles (anisotropic: 0.96× / 0.98×).
    anisotropic: bool = True
    ao_distance: float = 0.0  # metres for voxel AO; 0 = AO is the sky visibility (cones leaving the grid)

    def __post_init__(self):
        checks = [
            (16 <= self.resolution <= 512, f"resolution {self.resolution} out of range 16..512"),
            (_valid_cone_count(self.diffuse_cones), f"diffuse_cones {self.diffuse_cones} must be 5..9 or 13, 16, "
             f"19, … {MAX_CONES - 1}"),
            (isinstance(self.subrays, int) and 1 <= self.subrays <= MAX_SUBRAYS,
             f"subrays {self.subrays} out of range 1..{MAX_SUBRAYS}"),
            (self.bounce_cones == 0 or _valid_cone_count(self.bounce_cones),
             f"bounce_cones {self.bounce_cones} must be 0 (= diffuse_cones), 5..9 or 13, 16, 19, … {MAX_CONES - 1}"),
            (self.diffuse_aperture == 0 or 0 < self.diffuse_aperture < 90,
             f"diffuse_aperture {self.diffuse_aperture} must be 0 (derived) or in (0, 90) degrees"),
            (self.max_distance >= 0 and math.isfinite(self.max_distance), "max_distance must be ≥ 0 (0 = unlimited)"),
            (1 <= self.bounces <= 16, f"bounces {self.bounces} out of range 1..16"),
            (self.gathered_bounces == 0 or 2 <= self.gathered_bounces <= 16,
             f"gathered_bounces {self.gathered_bounces} must be 0 (gather all) or 2..16 (the tail needs a ratio)"),
            (0.05 <= self.step_multiplier <= 2.0, f"step_multiplier {self.step_multiplier} out of range 0.05..2"),
            (0.0 <= self.start_offset <= 8.0, f"start_offset {self.start_offset} out of range 0..8 voxels"),
            (0.0 <= self.roughness_cutoff <= 1.0, f"roughness_cutoff {self.roughness_cutoff} out of range 0..1"),
            (self.ao_distance >= 0 and math.isfinite(self.ao_distance), "ao_distance must be ≥ 0"),
            (self.indirect_scale in (1, 2, 4), f"indirect_scale {self.indirect_scale} must be 1, 2 or 4"),
            (0 <= self.temporal_frames <= 256, f"temporal_frames {self.temporal_frames} out of range 0..256"),
            (math.isfinite(self.cone_rotation), "cone_rotation must be finite"),
        ]
        for ok, message in checks:
            if not ok:
                raise ValueError(message)

    def key(self, kind: str) -> tuple:
        """The settings a pass reads: 'bounce', 'trace' (diffuse cones per pixel, upsampling, accumulation) or
        'specular' (resolution and anisotropy key the earlier passes)."""
        extra = {"bounce": CONE_FIELDS + ("bounce_cones", "bounces", "gathered_bounces"),
                 "trace": CONE_FIELDS + ("subrays", "ao_distance", "indirect_scale", "cone_rotation",
                                         "temporal_frames"),
                 "specular": ("max_distance", "step_multiplier", "start_offset", "specular_cone",
                              "roughness_cutoff")}[kind]
        d = asdict(self)
        if kind == "bounce" and self.bounce_cones:  # the gathers at voxel faces use bounce_cones, not diffuse_cones
            extra = tuple(name for name in extra if name != "diffuse_cones")
        return tuple((name, d[name]) for name in extra)


def _valid_cone_count(count) -> bool:
    try:
        ring_sizes(count)
        return True
    except (TypeError, ValueError):
        return False


def ring_sizes(count: int) -> list[int]:
    """Regions of the diffuse cone set, from the normal outward: [1, n − 1] for 5..9 cones (a cap and one ring),
    [1, m, 2m] for n = 1 + 3m, m = 4..10 (13, 16, … 31 cones: a cap and two rings, the outer one twice as many
    sectors so every region keeps about the same shape). Anything else is not a valid count."""
    n = int(count)
    if 5 <= n <= 9:
        return [1, n - 1]
    if (n - 1) % 3 == 0 and 4 <= (n - 1) // 3 <= (MAX_CONES - 1) // 3:
        return [1, (n - 1) // 3, 2 * (n - 1) // 3]
    raise ValueError(f"diffuse_cones {n}: must be 5..9, or 13, 16, 19, … {MAX_CONES - 1} (1 + 3m, two rings)")


def cone_table(count: int, aperture_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Diffuse cones: (unit directions (n, 3) in the normal's frame, z = normal; weights (n,); tan(half-angle) (n,)).

    The hemisphere is cut into n regions of equal solid angle 2π/n: a polar cap, then one or two rings
    (ring_sizes) each cut into m equal azimuthal sectors; the boundaries fall where the solid angle above them is
    a whole number of regions, 1 − cosθ_k = (regions so far)/n. Cone k stands for region k (ring [θa, θb], width
    Δφ = 2π/m):
      weight  w_k = ∫_region cosθ dω = Δφ·(sin²θb − sin²θa)/2; Σ w_k = π exactly, so a uniform radiance L gives
              E = Σ w_k·L = π·L, the exact cosine-weighted hemisphere integral;
      axis    the region's cosine-weighted mean direction: the normal for the cap; for a sector tilted by
              atan2(2·sin(Δφ/2)·(sin³θb − sin³θa), Δφ·(cos³θa − cos³θb)) from the normal (∫ sin²θ cosθ dθ and
              ∫ cos²θ sinθ dθ over the ring); the second ring is turned half a sector against the first;
      aperture half-angle of a cone of the region's solid angle, acos(1 − 1/n) (27.3° for 9 cones, 18.7° for 19),
              unless given.
    Why two rings are offered (measured, 64³, 160×120, against 2048-spp Cycles): in the volumetric march
    (trace_cone, which the bounce gathers still use) a cone's mip level is capped by its height above the surface it
    starts from, so a wide cone reads a footprint narrower than itself and over-weights what lies on its axis: 9
    cones of 27° gave Cornell one-bounce Diffuse Indirect rel-L1 0.23–0.27, 19 cones of 18.7° 0.16. The per-pixel
    sub-rays (vct_crossing.glsl) need no cap: 9 cones of 7 sub-rays give 0.100, 19 of 7 0.084 (VctSettings).
    """
    n = int(count)
    dirs, weights = [], []
    done, cos_a = 0, 1.0
    for ring, m in enumerate(ring_sizes(n)):
        done += m
        cos_b = 1.0 - done / n
        sin_a, sin_b = math.sqrt(max(0.0, 1.0 - cos_a * cos_a)), math.sqrt(max(0.0, 1.0 - cos_b * cos_b))
        dphi = 2.0 * math.pi / m
        weight = dphi * (sin_b ** 2 - sin_a ** 2) / 2.0
        if m == 1:
            dirs.append((0.0, 0.0, 1.0))
        else:
            tilt = math.atan2(2.0 * math.sin(dphi / 2.0) * (sin_b ** 3 - sin_a ** 3), dphi * (cos_a ** 3 - cos_b ** 3))
            turn = 0.5 * dphi if ring == 2 else 0.0
            dirs += [(math.sin(tilt) * math.cos(turn + k * dphi), math.sin(tilt) * math.sin(turn + k * dphi),
                      math.cos(tilt)) for k in range(m)]
        weights += [weight] * m
        cos_a = cos_b
    half = math.radians(aperture_deg) if aperture_deg > 0 else math.acos(1.0 - 1.0 / n)
    return np.array(dirs), np.array(weights), np.full(n, math.tan(half))


def subray_radius(count: int) -> float:
    """Where the sub-rays around a cone's axis go (vct_crossing.glsl), in units of tan(half-angle): cut the cone's
    disc into a central disc and a ring of count − 1 sectors, all of equal area (central radius r0 = 1/√count); a
    sub-ray goes through the centroid of its sector's radial extent, (2/3)(1 − r0³)/(1 − r0²) — 0.736 for 7."""
    if count <= 1:
        return 0.0
    r0 = 1.0 / math.sqrt(count)
    return (2.0 / 3.0) * (1.0 - r0 ** 3) / (1.0 - r0 ** 2)


def mip_levels(resolution: int) -> int:
    """Levels down to 4 voxels along the longest axis (64 → 5 levels: 64 … 4); cones wider than the coarsest voxel
    sample it with longer steps. Measured with levels down to 1 voxel: Diffuse Indirect rel-L1 at 8 bounces 0.005 –
    0.016 lower on Cornell / spot_room / courtyard, but the white furnace 94.8% → 89.8% of the exact light: texels
    that wide straddle a room's walls, and their mean coverage lets wide cones out."""
    return max(1, int(math.floor(math.log2(resolution))) - 1)


def vct_grid(scene: Scene, settings: VctSettings) -> Grid:
    """Grid.fit over the scene (1 empty margin voxel, origin snapped to whole cells, seed 004 §4.1), each axis
    padded up to a multiple of 2^(levels − 1) so every parent voxel has exactly 8 children at every level and
    the levels' texel centres nest (no half texels at borders)."""
    lo, hi = scene.bounds()
    g = Grid.fit(lo, hi, settings.resolution, margin_cells=1)
    align = 2 ** (mip_levels(settings.resolution) - 1)
    return Grid(g.origin, g.cell, tuple(-(-n // align) * align for n in g.size))


def level_sizes(grid: Grid, levels: int) -> list[tuple]:
    """Voxels per axis at each mip level (exact halvings: vct_grid pads the axes)."""
    return [tuple(int(n) >> level for n in grid.size) for level in range(levels)]


@dataclass
class Faces:
    """Six RGBA32F 3D textures, one per voxel face (outward normal +x, −x, +y, −y, +z, −z): rgb = outgoing
    radiance through that face, a = its coverage α_g (vct_inject.glsl). `flux`: π·cell²·Σ α_g·L_g (W, RGB)."""
    textures: list
    grid: Grid
    levels: int  # mip levels the volumes built from these faces get
    flux: list = None
    occupied: int = 0
    centroids: list = None  # vct_inject only: per face, xyz = where its surface points lie, w = ±α_g (vct_inject)
    missed: int = 0  # faces with coverage that caught no raster sample (lit at the face centre instead)

    def release(self):
        for t in self.textures + (self.centroids or []):
            t.release()


@dataclass
class ConeVolumes:
    """Filtered radiance (premultiplied rgb = α·L, a = α) with `levels` mip levels: 1 isotropic texture or 6
    anisotropic ones (direction of travel +x, −x, +y, −y, +z, −z). `owned` False: a view of another pass's
    volumes (vct_bounce with bounces = 1), which must not release them."""
    textures: list
    grid: Grid
    levels: int
    anisotropic: bool
    owned: bool = True
    faces: Faces | None = None  # the bounced face radiance these volumes were built from (vct_bounce only)
    bounce_stats: list = None
    # Anisotropic: where each texel's surfaces lie along each axis (vct_mipmap.glsl MODE_LAYERS). Geometry only, so
    # the bounce passes share the direct light's (layers_owned False).
    layers: object = None
    layers_owned: bool = True

    def release(self):
        if self.owned:
            for t in self.textures:
                t.release()
            if self.faces is not None:
                self.faces.release()
            if self.layers is not None and self.layers_owned:
                self.layers.release()


def _texture3d(ctx, size, levels: int = 1, zero: bool = False):
    """An RGBA32F volume; `zero`: filled with zeros, so passes may skip storing to empty voxels (llvmpipe image
    stores are slow: storing 12 zeros to every empty voxel took 1 s of vct_inject at 128³)."""
    import moderngl

    from .gpu_context import zero_texture

    t = ctx.texture3d(tuple(int(n) for n in size), 4, None, dtype="f4")
    if zero:
        zero_texture(ctx, t)
    t.repeat_x = t.repeat_y = t.repeat_z = False
    if levels > 1:
        t.build_mipmaps(0, levels - 1)  # allocates the chain; every level is then overwritten by vct_mipmap.glsl
        t.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    else:
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return t


def _units(prog, name: str, textures: list, first: int) -> int:
    """Bind `textures` to consecutive texture units from `first` and point sampler (array) `name` at them."""
    for i, t in enumerate(textures):
        t.use(location=first + i)
    if name in prog:
        units = list(range(first, first + len(textures)))
        prog[name].value = units if prog[name].array_length > 1 else units[0]
    return first + len(textures)


def _volume_units(prog, volumes: ConeVolumes, first: int) -> int:
    """Bind the cone volumes (sampler array u_volume) and, anisotropic, their layer volume (u_layers) from unit
    `first`; returns the next free unit."""
    unit = _units(prog, "u_volume", volumes.textures, first)
    return _units(prog, "u_layers", [volumes.layers] if volumes.layers is not None else [], unit)


def _dispatch(prog, size, local: int = 4):
    prog.run(*((int(n) + local - 1) // local for n in size))


def _grid_uniforms(prog, grid: Grid, levels: int = 1):
    direct._set(prog, "u_grid_origin", tuple(float(c) for c in grid.origin))
    direct._set(prog, "u_cell", float(grid.cell))
    direct._set(prog, "u_grid_size", tuple(int(n) for n in grid.size))
    direct._set(prog, "u_max_lod", float(levels - 1))


def voxelize_scene(ctx, programs, scene: Scene, geometry, textures: list, grid: Grid):
    """The shared voxelizer (rasterised, exact areas) on the VCT grid."""
    from .voxelize import voxelize

    return voxelize(ctx, programs, scene, geometry, textures, grid)


INJECT_SAMPLES = 2  # raster samples per voxel edge: ~4 surface points per voxel face; slivers fall back (vct_inject)


def inject(ctx, programs, scene: Scene, geometry, textures: list, vox, shadows, levels: int) -> Faces:
    """Direct light reflected through every voxel face: surface points rasterised along their dominant axis and lit
    exactly as in direct_light.glsl (vct_inject_raster.glsl), then averaged per face (vct_inject.glsl)."""
    import moderngl

    grid = vox.grid
    nx, ny, nz = grid.size
    faces = Faces([_texture3d(ctx, grid.size, zero=True) for _ in range(6)], grid, levels,
                  centroids=[_texture3d(ctx, grid.size, zero=True) for _ in range(6)])
    acc = ctx.texture3d((8 * nx, ny, 6 * nz), 1, dtype="u4")
    acc.filter = (moderngl.NEAREST, moderngl.NEAREST)
    try:
        clear = programs.compute("vct_inject.glsl", {"MODE_CLEAR": None})
        acc.bind_to_image(0, read=False, write=True)
        direct._set(clear, "u_grid_size", grid.size)
        _dispatch(clear, grid.size)
        ctx.memory_barrier()

        prog = programs.raster("vct_inject_raster.glsl")
        side = max(grid.size) * INJECT_SAMPLES
        _grid_uniforms(prog, grid)
        _light_uniforms(prog, shadows, unit=2)
        for name, value in (("u_samples", float(INJECT_SAMPLES)), ("u_viewport", (float(side), float(side)))):
            direct._set(prog, name, value)
        acc.bind_to_image(0, read=True, write=True)
        vao = ctx.vertex_array(prog, [(geometry.vbo, "3f 12x 2f 12x", "in_position", "in_uv")])
        fbo = ctx.empty_framebuffer((side, side))
        try:
            fbo.use()
            fbo.viewport = (0, 0, side, side)
            ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
            direct.draw_by_material(prog, scene, geometry, textures, vao=vao)  # material uniforms, texture unit 0
        finally:
            vao.release()
            fbo.release()
        ctx.memory_barrier()

        for outputs, defines in ((faces.textures, {}), (faces.centroids, {"WRITE_CENTROIDS": None})):
            prog = programs.compute("vct_inject.glsl", {"MODE_RESOLVE": None, **defines})
            unit = _units(prog, "u_area", [vox.area], 0)
            unit = _units(prog, "u_albedo", [vox.albedo], unit)
            unit = _units(prog, "u_acc", [acc], unit)
            _light_uniforms(prog, shadows, unit)
            _grid_uniforms(prog, grid)
            for i, t in enumerate(outputs):
                t.bind_to_image(i, read=False, write=True)
            _dispatch(prog, grid.size)
            ctx.memory_barrier()
    finally:
        acc.release()
    faces.flux, faces.occupied, faces.missed = face_flux(ctx, programs, faces)
    return faces


def _light_uniforms(prog, shadows, unit: int) -> None:
    """The lights, shadow views, polygons and shadow atlas of direct_eval.glsl."""
    shadows.depth.use(location=unit)
    direct._set(prog, "u_shadow_atlas", unit)
    direct._set(prog, "u_atlas_texel", (1.0 / shadows.size[0], 1.0 / shadows.size[1]))
    direct._set(prog, "u_light_count", shadows.light_count)
    shadows.light_ssbo.bind_to_storage_buffer(0)
    shadows.view_ssbo.bind_to_storage_buffer(1)
    shadows.polygon_ssbo.bind_to_storage_buffer(2)


def face_flux(ctx, programs, faces: Faces) -> tuple[list, int, int]:
    """(π·cell²·Σ_voxels Σ_g α_g·L_g per RGB channel — the outgoing flux (W) the faces carry; occupied voxels;
    faces lit at their centre for want of raster samples), summed per row on the GPU (MODE_FLUX), rows here."""
    nx, ny, nz = faces.grid.size
    out = ctx.buffer(reserve=ny * nz * 32)
    try:
        prog = programs.compute("vct_mipmap.glsl", {"MODE_FLUX": None})
        unit = _units(prog, "u_src", faces.textures, 0)
        _units(prog, "u_centroid", faces.centroids or faces.textures, unit)
        direct._set(prog, "u_has_centroids", faces.centroids is not None)
        direct._set(prog, "u_dst_size", (int(nx), int(ny), int(nz)))
        out.bind_to_storage_buffer(0)
        _dispatch(prog, (ny, nz, 1), local=8)
        ctx.memory_barrier()
        rows = np.frombuffer(out.read(), np.float32).reshape(-1, 2, 4).astype(np.float64)
    finally:
        out.release()
    flux = rows[:, 0, :3].sum(axis=0) * math.pi * faces.grid.cell ** 2
    return [float(c) for c in flux], int(round(rows[:, 0, 3].sum())), int(round(rows[:, 1, 0].sum()))


def build_volumes(ctx, programs, faces: Faces, anisotropic: bool, into: ConeVolumes | None = None,
                  layers=None) -> ConeVolumes:
    """Level 0 from the face radiances, then each level from the one below (vct_mipmap.glsl, seed 004 §4.4), and,
    anisotropic, the layer volume (from faces.centroids, or `layers` shared from the volumes of the same geometry).
    `into`: rebuild existing volumes in place (vct_bounce) instead of allocating new ones."""
    grid = faces.grid
    sizes = level_sizes(grid, faces.levels)
    count = 6 if anisotropic else 1
    vols = into or ConeVolumes([_texture3d(ctx, grid.size, len(sizes)) for _ in range(count)], grid, len(sizes),
                               anisotropic)
    variant = {"MODE_ANISO": None} if anisotropic else {}
    prog = programs.compute("vct_mipmap.glsl", {"MODE_BASE": None, **variant})
    _units(prog, "u_src", faces.textures, 0)
    for unit, t in enumerate(vols.textures):
        t.bind_to_image(unit, read=False, write=True, level=0)
    direct._set(prog, "u_dst_size", sizes[0])
    _dispatch(prog, sizes[0])
    ctx.memory_barrier()
    prog = programs.compute("vct_mipmap.glsl", {"MODE_DOWN": None, **variant})
    _units(prog, "u_src", vols.textures, 0)
    for level in range(1, len(sizes)):
        for unit, t in enumerate(vols.textures):
            t.bind_to_image(unit, read=False, write=True, level=level)
        direct._set(prog, "u_dst_size", sizes[level])
        direct._set(prog, "u_level", level)
        _dispatch(prog, sizes[level])
        ctx.memory_barrier()
    if anisotropic and layers is not None:
        vols.layers, vols.layers_owned = layers, False
    elif anisotropic and vols.layers is None:
        vols.layers, vols.layers_owned = build_layers(ctx, programs, faces, vols), True
    return vols


def build_layers(ctx, programs, faces: Faces, vols: ConeVolumes):
    """The layer volume of anisotropic `vols` (vct_mipmap.glsl MODE_LAYERS), every level."""
    grid = faces.grid
    sizes = level_sizes(grid, vols.levels)
    layers = _texture3d(ctx, grid.size, len(sizes))
    prog = programs.compute("vct_mipmap.glsl", {"MODE_LAYERS": None})
    unit = _units(prog, "u_src", vols.textures, 0)
    unit = _units(prog, "u_centroid", faces.centroids or faces.textures, unit)
    _units(prog, "u_layers_src", [layers], unit)
    direct._set(prog, "u_has_centroids", faces.centroids is not None)
    direct._set(prog, "u_grid_origin", tuple(float(c) for c in grid.origin))
    direct._set(prog, "u_cell", float(grid.cell))
    for level, size in enumerate(sizes):
        layers.bind_to_image(0, read=False, write=True, level=level)
        direct._set(prog, "u_dst_size", size)
        direct._set(prog, "u_level", level)
        _dispatch(prog, size)
        ctx.memory_barrier()
    return layers


# The cone passes live in vct_cones.py (vct.py stays a readable size); re-exported here for pipeline.py and tests.
from .vct_cones import bounce, read_ao, read_level, render_info, trace  # noqa: E402,F401
