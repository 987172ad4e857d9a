"""The render pipeline: a scene and settings in, Cycles-named passes (numpy) and per-pass seconds out.

Passes and their inputs (a pass re-runs only when one of its inputs changed — see pass_cache.py):
    geometry      ← scene geometry
    textures      ← materials (images)
    shadow_maps   ← geometry, materials (emissive triangles), lights, shadow settings
    gbuffer       ← geometry, materials, camera, resolution
    direct_light  ← gbuffer, shadow_maps
    compose       ← everything above, world      (CPU: passes as numpy, Combined)
"""
from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass, field

import numpy as np

from . import direct, lpv, vct, vct_specular, vct_temporal, vct_upsample
from .light_buffers import ShadowSettings
from .lpv import LpvSettings
from .pass_cache import PassCache
from .programs import ProgramCache
from .scene import Scene, _hash_into
from .vct import VctSettings

METHODS = ("none", "lpv", "vct")
PASS_NAMES = ("Combined", "Diffuse Direct", "Diffuse Indirect", "Diffuse Color", "Glossy Indirect", "Glossy Color",
              "Emission", "AO", "Normal", "Position", "Depth")
BACKGROUND_DEPTH = 1e10  # Cycles writes 1e10 to the Depth pass where no geometry was hit


class SceneError(ValueError):
    """The scene cannot be rendered as given (message is for the user)."""


@dataclass(frozen=True)
class RenderSettings:
    method: str = "none"
    width: int = 640
    height: int = 480
    shadow: ShadowSettings = field(default_factory=ShadowSettings)
    lpv: LpvSettings = field(default_factory=LpvSettings)
    vct: VctSettings = field(default_factory=VctSettings)

    def key(self) -> str:
        return repr(sorted(asdict(self).items()))


@dataclass
class RenderResult:
    passes: dict  # name -> (H, W, C) float32, rows top-to-bottom
    timings: dict  # pass name -> seconds (0.0 when the pass was skipped), plus "total"
    skipped: list  # passes whose cached result was still valid
    warnings: list
    statistics: dict
    method: str
    resolution: tuple
    info: dict = field(default_factory=dict)  # method details: LPV iterations, injected flux, grids


def _hash(*parts) -> str:
    h = hashlib.sha1()
    for p in parts:
        _hash_into(h, p)
    return h.hexdigest()


def check_renderable(scene: Scene, settings: RenderSettings) -> None:
    if settings.method not in METHODS:
        raise SceneError(f"unknown method '{settings.method}' (choose from {', '.join(METHODS)})")
    if scene.camera is None:
        raise SceneError("the scene has no camera")
    if settings.width < 1 or settings.height < 1 or settings.width > 16384 or settings.height > 16384:
        raise SceneError(f"resolution {settings.width}x{settings.height} is out of range (1..16384)")


class Pipeline:
    """Owns the GL resources of one context and re-runs only the passes whose inputs changed."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.programs = ProgramCache(ctx)
        self.cache = PassCache(finish=ctx.finish)

    def render(self, scene: Scene, settings: RenderSettings) -> RenderResult:
        import time

        check_renderable(scene, settings)
        start = time.perf_counter()
        ctx, programs, cache = self.ctx, self.programs, self.cache
        cache.begin_frame()
        k_geometry = _hash(scene.positions, scene.normals, scene.uvs, scene.material_index)
        k_materials = _hash(scene.materials, scene.textures)
        k_lights = _hash(scene.lights)
        k_camera = _hash(scene.camera, scene.pixel_aspect, settings.width, settings.height)
        k_world = _hash(scene.world)

        geometry = cache.run("geometry", (k_geometry,), lambda: direct.upload_geometry(ctx, programs, scene))
        textures = cache.run("textures", (k_materials,), lambda: direct.upload_textures(ctx, scene))
        k_shadow = (k_geometry, k_materials, k_lights, repr(settings.shadow))
        shadows = cache.run("shadow_maps", k_shadow,
                            lambda: direct.render_shadow_atlas(ctx, programs, scene, geometry, settings.shadow))
        k_gbuffer = (k_geometry, k_materials, k_camera)
        gbuffer = cache.run("gbuffer", k_gbuffer, lambda: direct.render_gbuffer(
            ctx, programs, scene, geometry, textures, settings.width, settings.height))
        k_direct = (k_gbuffer, k_shadow)
        direct_tex = cache.run("direct_light", k_direct,
                               lambda: direct.render_direct_light(ctx, programs, gbuffer, shadows))
        indirect_tex, glossy_tex, k_indirect, info = None, None, None, {}
        if settings.method == "lpv":
            indirect_tex, k_indirect, info = self._lpv(scene, settings, geometry, textures, shadows, gbuffer,
                                                       k_geometry, k_materials, k_shadow, k_gbuffer)
        elif settings.method == "vct":
            indirect_tex, glossy_tex, k_indirect, info = self._vct(scene, settings, geometry, textures, shadows,
                                                                   gbuffer, k_geometry, k_materials, k_shadow,
                                                                   k_gbuffer)

        def compose():
            indirect = None if indirect_tex is None else direct.read_texture(indirect_tex, 4)
            return compose_passes(gbuffer, direct_tex, scene.world.color,
                                  None if indirect is None else indirect[..., :3],
                                  None if glossy_tex is None else direct.read_texture(glossy_tex, 3),
                                  None if indirect is None or settings.method != "vct" else indirect[..., 3])
        passes = cache.run("compose", (k_direct, k_indirect, k_world), compose)
        timings = dict(cache.timings)
        timings["total"] = time.perf_counter() - start
        return RenderResult(passes=passes, timings=timings, skipped=list(cache.skipped),
                            warnings=list(scene.warnings) + list(shadows.warnings),
                            statistics=scene.statistics(), method=settings.method,
                            resolution=(settings.width, settings.height), info=info)

    def _lpv(self, scene, settings, geometry, textures, shadows, gbuffer, k_geometry, k_materials, k_shadow,
             k_gbuffer):
        """LPV passes: rsm ← shadow views; geometry_volume ← geometry, grids; lpv_inject ← rsm, grids, world;
        lpv_propagate ← injection, geometry volume, LPV settings (the transport: the gather's bounces or the
        propagation, lpv.gather_all / lpv.propagate_all); lpv_lighting ← gbuffer, transport."""
        ctx, programs, cache, s = self.ctx, self.programs, self.cache, settings.lpv
        grids = lpv.cascade_grids(scene, s)
        k_grids = tuple(g.key() for g in grids)
        k_rsm = (k_shadow, s.rsm_resolution)
        rsm = cache.run("rsm", k_rsm, lambda: lpv.render_rsm(ctx, programs, scene, geometry, textures, shadows,
                                                             s.rsm_resolution))
        k_gv = (k_geometry, k_materials, k_grids, s.occlusion)
        gvs = cache.run("geometry_volume", k_gv, lambda: lpv.geometry_volumes(
            ctx, programs, scene, geometry, textures, grids) if s.occlusion else [None] * len(grids))
        gather_vpls = s.gather_vpls if s.gathers else 0
        k_inject = (k_rsm, k_grids, k_gv, _hash(scene.world), s.rsm_downsample, gather_vpls)
        states = cache.run("lpv_inject", k_inject, lambda: lpv.inject_all(
            ctx, programs, rsm, shadows, grids, scene.world.color, gvs, s.rsm_downsample, gather_vpls))
        k_prop = (k_inject, k_gv, repr(s))
        if s.octree_levels:  # seed 002 (lpv_octree.py): index volume, downsample, per-level propagation, merge
            from . import lpv_octree as lo
            geo = cache.run("lpv_octree_geometry", (k_gv, s.octree_levels),
                            lambda: lo.build_geometry(ctx, gvs[0], grids[0], s.octree_levels))
            tree = cache.run("lpv_downsample", (k_inject, s.octree_levels),
                             lambda: lo.downsample(ctx, programs, states[0], geo))
            stats = cache.run("lpv_propagate", k_prop, lambda: lo.propagate_levels(ctx, programs, tree, geo, s))
            merged = cache.run("lpv_merge", k_prop, lambda: lo.merge(ctx, programs, tree, geo))
            states, gvs, s = [merged], [None], lo.lookup_settings(s)
        else:
            transport = lpv.gather_all if s.gathers else lpv.propagate_all
            stats = cache.run("lpv_propagate", k_prop, lambda: transport(ctx, programs, states, gvs, s))
        k_light = (k_gbuffer, k_prop)
        indirect = cache.run("lpv_lighting", k_light, lambda: lpv.lighting(ctx, programs, gbuffer, states, gvs, s))
        return indirect, k_light, stats

    def _vct(self, scene, settings, geometry, textures, shadows, gbuffer, k_geometry, k_materials, k_shadow,
             k_gbuffer):
        """VCT passes (seed 004): vct_voxelize ← geometry, materials, grid; vct_inject ← voxels, shadow maps (lights);
        vct_mipmap ← injection, anisotropy; vct_bounce ← mipmaps, world, cone settings, bounces;
        vct_specular ← gbuffer, bounced volumes, specular settings; vct_trace ← gbuffer, bounced volumes, trace
        settings, accumulation frame; vct_upsample ← vct_trace (indirect_scale > 1); vct_accumulate ← the upsampled
        trace (temporal_frames > 1). Returns (Diffuse Indirect + AO texture, Glossy Indirect texture, key, info)."""
        ctx, programs, cache, s = self.ctx, self.programs, self.cache, settings.vct
        grid = vct.vct_grid(scene, s)
        levels = vct.mip_levels(s.resolution)
        world = tuple(float(c) for c in scene.world.color[:3])
        k_vox = (k_geometry, k_materials, grid.key())
        vox = cache.run("vct_voxelize", k_vox,
                        lambda: vct.voxelize_scene(ctx, programs, scene, geometry, textures, grid))
        k_inject = (k_vox, k_shadow, levels)
        faces = cache.run("vct_inject", k_inject, lambda: vct.inject(ctx, programs, scene, geometry, textures, vox,
                                                                shadows, levels))
        k_mip = (k_inject, s.anisotropic)
        volumes = cache.run("vct_mipmap", k_mip, lambda: vct.build_volumes(ctx, programs, faces, s.anisotropic))
        k_bounce = (k_mip, world, s.key("bounce"))
        bounced = cache.run("vct_bounce", k_bounce,
                            lambda: vct.bounce(ctx, programs, vox, faces, volumes, s, world))
        k_spec = (k_gbuffer, k_bounce, s.key("specular"))
        glossy = cache.run("vct_specular", k_spec, lambda: vct_specular.specular(ctx, programs, gbuffer, faces,
                                                                                  bounced, s, world))
        # Temporal accumulation: the trace's inputs key the history; while it holds fewer than temporal_frames
        # frames, the frame index makes the keys new, so trace (and upsample) run again with the next jitter.
        base = (k_gbuffer, k_bounce, s.key("trace"))
        accumulating = s.temporal_frames > 1
        prior = cache.entries.get("vct_accumulate")
        frame = vct_temporal.frame_index(prior.value if prior and accumulating else None, base, s.temporal_frames)
        rotation = vct_temporal.jitter_deg(s, frame) if accumulating else s.cone_rotation
        k_trace = (base, frame)
        traced = cache.run("vct_trace", k_trace, lambda: vct.trace(ctx, programs, gbuffer, faces, bounced, s, world,
                                                                   rotation))
        info = vct.render_info(faces, bounced, s)
        info["specular_pixels"] = glossy["traced"]
        indirect = traced["indirect"]
        if s.indirect_scale > 1:
            up = cache.run("vct_upsample", k_trace, lambda: vct_upsample.upsample(
                ctx, programs, gbuffer, traced, faces, bounced, s, world, rotation))
            indirect, info["fixup_pixels"] = up["indirect"], up["fixup"]
        if accumulating:
            history = cache.run("vct_accumulate", k_trace, lambda: vct_temporal.accumulate(
                ctx, programs, prior.value if prior else None, indirect, base, frame))
            indirect = history.texture
            info["temporal"] = {"frames": history.frames, "of": s.temporal_frames,
                                "done": history.frames >= s.temporal_frames}
        return indirect, glossy["glossy"], (k_trace, k_spec), info

    def release(self) -> None:
        self.cache.clear()
        self.programs.release()


def compose_passes(gbuffer, direct_tex, world_color, indirect: np.ndarray | None = None,
                   glossy: np.ndarray | None = None, ao: np.ndarray | None = None) -> dict:
    """Read the GPU results back and build the Cycles-named passes; Combined = (direct+indirect)·colour +
    Glossy Indirect·Glossy Color + emission. `indirect`, `glossy`: (H, W, 3) Diffuse / Glossy Indirect; `ao`: (H, W)
    voxel AO. Methods without them get zeros (AO: 1 on geometry), so every method writes the same passes."""
    position = direct.read_texture(gbuffer.textures["position"])
    hit = position[..., 3:4] > 0.5
    normal = direct.read_texture(gbuffer.textures["normal"])
    albedo = direct.read_texture(gbuffer.textures["albedo"], 3) * hit
    glossy_color = direct.read_texture(gbuffer.textures["glossy"], 3) * hit
    emission = direct.read_texture(gbuffer.textures["emission"], 3) * hit
    # Cycles divides its light passes by Diffuse Color per channel and writes 0 where that colour is 0
    # (safe_divide_even_color), so a surface with no diffuse part shows no diffuse light; glossy likewise.
    has_diffuse = albedo > 0
    diffuse_direct = direct.read_texture(direct_tex, 3) * has_diffuse
    diffuse_indirect = np.zeros_like(diffuse_direct) if indirect is None else indirect * has_diffuse
    glossy_indirect = np.zeros_like(diffuse_direct) if glossy is None else glossy * (glossy_color > 0)
    ao_pass = np.repeat((hit[..., 0] if ao is None else ao * hit[..., 0])[..., None], 3, axis=2)
    combined = np.empty(albedo.shape[:2] + (4,), np.float32)
    combined[..., :3] = np.where(hit, (diffuse_direct + diffuse_indirect) * albedo + glossy_indirect * glossy_color
                                 + emission, np.asarray(world_color, np.float32)[:3])
    combined[..., 3] = 1.0  # the world is visible to the camera (film not transparent), as in Cycles' default
    depth = np.where(hit, normal[..., 3:4], BACKGROUND_DEPTH).astype(np.float32)
    return {
        "Combined": combined,
        "Diffuse Direct": diffuse_direct.astype(np.float32),
        "Diffuse Indirect": diffuse_indirect.astype(np.float32),
        "Diffuse Color": albedo.astype(np.float32),
        "Glossy Indirect": glossy_indirect.astype(np.float32),
        "Glossy Color": glossy_color.astype(np.float32),
        "Emission": emission.astype(np.float32),
        "AO": ao_pass.astype(np.float32),
        "Normal": (normal[..., :3] * hit).astype(np.float32),
        "Position": (position[..., :3] * hit).astype(np.float32),
        "Depth": depth,
    }
