# SPDX-License-Identifier: GPL-3.0-or-later
"""The render pipeline: a scene and settings in, Cycles-named passes (numpy) and per-pass seconds out.

Passes and their inputs (a pass re-runs only when one of its inputs changed — see gl/pass_cache.py):
    geometry      ← scene geometry
    textures      ← materials (images)
    emitter_shells← geometry, emission (closed emitters: common/emitters.py)
    shadow_maps   ← geometry, emission (emissive triangles), lights, shadow settings, which closed emitters hold
                    the camera, world
      shadow_depth← geometry, the shadow views (their depth atlas: a light's power or the world's colour
                    moves no view, so it is kept; a light's move redraws its tiles, an object's move the part of
                    each tile it covers: direct/shadows.render_depth)
      light_sources← the emissive triangles, the scene's bounds, shadow settings, the closed emitters (the emissive
                    meshes' lights and the sky's views: common/lights.static_lights; an object move keeps them)
    gbuffer       ← geometry, materials, camera, resolution
    sky_visibility← geometry, shading, camera, the sky's shadow views (its visible shares: a world colour edit or
                    another light's move keeps them; after an object's move, each pixel redoes only the tests that read
                    a redrawn texel: direct/sky.SkyUpdate)
    direct_light  ← geometry, shading, camera, shadow_maps, sky_visibility (scene.material_keys: a dielectric's
                    base colour edit keeps both); after an object's move, the pixels it cannot change keep their light
                    (direct/lighting.Relight)
    <method>      ← the above (lpv/passes.py, vct/passes.py: the indirect light)
    compose       ← everything above, world      (CPU: passes as numpy, Combined)

render_surface() runs the same passes on a surface atlas's G-buffer (surface/): the viewport's view-independent
lighting.

A GI method is one entry of METHOD_PASSES: a function that takes the FrameInputs and returns a MethodOutput.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from .common import emitters as em
from .common import lights as lb
from .compose import compose_passes
from .direct import gbuffer as gb
from .direct import geometry as geo
from .direct import lighting, shadows as sh, sky
from .gl.bind import read_texture
from .gl.pass_cache import PassCache
from .gl.programs import ProgramCache
from .lpv import passes as lpv_passes
from .scene import Scene, hash_parts, material_keys
from .settings import METHODS, RenderSettings, check_method, check_renderable
from .surface import gbuffer as sgb
from .surface.atlas import SurfaceAtlas
from .common.principled import material_lut
from .surface.mesh import draw_arrays
from .vct import passes as vct_passes


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


@dataclass
class SurfaceLight:
    """render_surface's result: the atlas and, per texel of both pages, (2H, W, 3) float32, rows bottom-up; the
    indirect light in its own (coarser) atlas's layout."""
    atlas: SurfaceAtlas
    direct: np.ndarray  # Diffuse Direct (irradiance / π)
    indirect: np.ndarray  # Diffuse Indirect (zeros for method "none")
    base: np.ndarray  # (H, W, 3): the front page's base colours (surface/gbuffer.base_colors)
    mesh: dict  # the viewport's vertex arrays (surface/mesh.draw_arrays)
    timings: dict
    skipped: list
    warnings: list
    method: str
    statistics: dict = field(default_factory=dict)  # Scene.statistics(): triangles, lights by type, bounds
    info: dict = field(default_factory=dict)  # the method's details, as RenderResult.info (grids, bounces)
    indirect_atlas: SurfaceAtlas | None = None  # the layout `indirect` is in (None: `atlas`)
    indirect_base: np.ndarray | None = None  # base colours in that layout
    material_lut: np.ndarray | None = None  # the materials' Principled table (common/principled.material_lut)


@dataclass
class FrameInputs:
    """What a method's passes read: the GL context, programs and pass cache; the scene and settings; the direct
    passes' outputs; and `keys`, the content keys of the scene parts and passes ("geometry", "materials",
    "emission", "shading", "lights", "camera", "world", "shadow", "gbuffer", "direct") that the method's own pass
    keys build on."""
    ctx: object
    programs: ProgramCache
    cache: PassCache
    scene: Scene
    settings: RenderSettings
    geometry: geo.GeometryBuffers
    textures: list
    shadows: sh.ShadowAtlas
    gbuffer: gb.GBuffer
    keys: dict


@dataclass
class PointLight:
    """render_points' result: per point, (N, 3) float32."""
    direct: np.ndarray  # Diffuse Direct (irradiance / π)
    indirect: np.ndarray  # Diffuse Indirect (zeros for method "none")
    timings: dict
    warnings: list
    method: str


def surface_settings(settings: RenderSettings) -> RenderSettings:
    """Settings for light at surface points rather than pixels: the per-pixel refinements that need a camera are
    off — VCT's upsampling (its neighbours would be other triangles' texels), temporal accumulation and the
    specular cone (no view direction)."""
    vct = replace(settings.vct, indirect_scale=1, temporal_frames=0, specular_cone=False)
    return replace(settings, vct=vct)


def indirect_image(out, shape) -> np.ndarray:
    """A method's Diffuse Indirect on surface samples, rows bottom-up; zeros of `shape` without one."""
    if out is None or out.indirect is None:
        return np.zeros(shape, np.float32)
    return read_texture(out.indirect, 3)[::-1]


def unlit(frame) -> bool:
    """Whether nothing lights the scene: no light records (lamps without power or unable to reach it are left out,
    emissive meshes and a world with colour are lights: common/lights.py)."""
    return len(frame.shadows.buffers.lights) == 0


def method_info(out, frame) -> dict:
    """The method's details (RenderResult.info), with "skipped_work": the lights that cannot light the scene and
    what the method left out."""
    info = dict(out.info) if out else {}
    lights = list(frame.shadows.buffers.skipped or [])
    info["skipped_work"] = lights + list(info.get("skipped_work", []))
    if out is None and frame.settings.method == "none":
        info["skipped_work"].append("indirect light: method none")
    elif out is None:
        info["skipped_work"].append("indirect light: nothing lights the scene (no lamp with power, no emission, a "
                                    "black world), so no GI pass ran")
    return info


def surface_base(scene: Scene, atlas: SurfaceAtlas) -> np.ndarray:
    return sgb.base_colors(scene, atlas, sgb.surface_points(scene, atlas))


METHOD_PASSES = {"lpv": lpv_passes.run, "vct": vct_passes.run}  # "none": direct light only
assert set(METHOD_PASSES) | {"none"} == set(METHODS)


class Pipeline:
    """Owns the GL resources of one context and re-runs only the passes whose inputs changed."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.programs = ProgramCache(ctx)
        self.cache = PassCache(finish=ctx.finish, keep={**lpv_passes.KEEP, **vct_passes.KEEP})

    def render(self, scene: Scene, settings: RenderSettings, checked: bool = False) -> RenderResult:
        """`checked`: the caller ran settings.check_renderable on these (Engine.submit_render does, on its own
        thread: an unchanged frame then costs its keys and little else)."""
        if not checked:
            check_renderable(scene, settings)
        start = time.perf_counter()
        self.cache.begin_frame()
        frame = self._direct_passes(scene, settings)
        direct_tex = self._direct_light(frame, frame.textures.lut, camera=True)
        out = self._method_output(frame)

        def compose():
            indirect = None if out is None or out.indirect is None else read_texture(out.indirect, 4)
            return compose_passes(frame.gbuffer, direct_tex, scene.world.color,
                                  None if indirect is None else indirect[..., :3],
                                  None if out is None or out.glossy is None else read_texture(out.glossy, 4),
                                  indirect[..., 3] if indirect is not None and out.has_ao else None)
        passes = self.cache.run("compose", (frame.keys["gbuffer"], frame.keys["direct"], out and out.key,
                                            frame.keys["world"]), compose)
        timings = dict(self.cache.timings)
        timings["total"] = time.perf_counter() - start
        return RenderResult(passes=passes, timings=timings, skipped=list(self.cache.skipped),
                            warnings=list(scene.warnings) + list(frame.shadows.warnings),
                            statistics=scene.statistics(), method=settings.method,
                            resolution=(settings.width, settings.height), info=method_info(out, frame))

    def render_surface(self, scene: Scene, settings: RenderSettings, atlas: SurfaceAtlas,
                       indirect_atlas: SurfaceAtlas | None = None) -> SurfaceLight:
        """Diffuse Direct and Diffuse Indirect at every texel of a surface atlas (surface/atlas.py): the same passes
        as render(), on the atlas's G-buffer instead of the camera's. View-independent, so the viewport draws it
        from any camera. The indirect light may be computed on a coarser atlas of the same triangles (it varies
        slowly; its gather is the expensive part)."""
        start = time.perf_counter()
        settings = surface_settings(settings)
        self.cache.begin_frame()
        direct, frame = self._direct_at(scene, settings, sgb.atlas_samples(scene, atlas))
        base = surface_base(scene, atlas)
        indirect_base = base
        if indirect_atlas is not None and indirect_atlas is not atlas:
            frame = self._direct_passes(scene, settings, sgb.atlas_samples(scene, indirect_atlas))
            indirect_base = surface_base(scene, indirect_atlas)
        indirect_atlas = indirect_atlas or atlas
        out = self._method_output(frame)
        indirect = indirect_image(out, (2 * indirect_atlas.height, indirect_atlas.width, 3))
        timings = dict(self.cache.timings)
        timings["total"] = time.perf_counter() - start
        return SurfaceLight(atlas, direct, indirect, base, draw_arrays(scene, atlas, indirect_atlas), timings,
                            list(self.cache.skipped), list(scene.warnings) + list(frame.shadows.warnings),
                            settings.method, scene.statistics(), method_info(out, frame), indirect_atlas,
                            indirect_base, material_lut(scene.materials))

    def render_points(self, scene: Scene, settings: RenderSettings, positions, normals) -> PointLight:
        """Diffuse Direct and Diffuse Indirect (irradiance / π) at N points with normals (N, 3): the passes of
        render_surface on a G-buffer of those points (a bake to mesh vertices)."""
        start = time.perf_counter()
        settings = surface_settings(settings)
        self.cache.begin_frame()
        direct, frame = self._direct_at(scene, settings, sgb.point_samples(positions, normals))
        indirect = indirect_image(self._method_output(frame), direct.shape)
        n = len(np.asarray(positions).reshape(-1, 3))
        timings = dict(self.cache.timings)
        timings["total"] = time.perf_counter() - start
        return PointLight(direct.reshape(-1, 3)[:n], indirect.reshape(-1, 3)[:n], timings,
                          list(scene.warnings) + list(frame.shadows.warnings), settings.method)

    def _direct_at(self, scene, settings, samples) -> tuple[np.ndarray, FrameInputs]:
        """Diffuse Direct on `samples`' G-buffer as (H, W, 3), rows bottom-up (the samples' own order), and the
        frame the method's passes read."""
        check_method(settings)  # no camera needed
        frame = self._direct_passes(scene, settings, samples)
        tex = self._direct_light(frame, None)
        return tex["diffuse"][::-1], frame

    def _direct_light(self, frame, material_lut, camera: bool = False) -> dict:
        """The direct_light pass, and before it the sky light's visibility, kept apart (sky_visibility): it depends
        on the G-buffer and the sky's own shadow maps, not on any light's colour nor on the other lights, so a world
        or light colour edit and another light's move skip it. `camera`: the G-buffer is the camera's (an object's
        move then re-lights only the pixels it can change: _relight, _sky_update)."""
        maps, scene = frame.shadows.maps, frame.scene
        made_from = (maps.serial, maps.generation, scene.surface_arrays(), frame.keys["gbuffer"])
        k_sky = (frame.keys["direct"][0], sh.sky_key(frame.shadows))

        def sky_visibility():
            update = self._sky_update(frame, k_sky) if camera else None
            out = sky.render_sky_visibility(self.ctx, self.programs, frame.gbuffer, frame.shadows, material_lut,
                                            update)
            if out is not None:
                out.made_from = made_from
            return out
        shares = self.cache.run("sky_visibility", k_sky, sky_visibility)
        # Each group of lights keeps its images while its lights do not change (direct/lighting.light_groups): from
        # the kept output of the same G-buffer and shadow settings, a light's edit re-lights that light alone.
        prior = self.cache.prior("direct_light", lambda k: k[0] == frame.keys["direct"][0]
                                 and k[1][4] == frame.keys["shadow"][4])
        relight = self._relight(frame) if camera and prior is None else None
        return self.cache.run("direct_light", frame.keys["direct"], lambda: {**lighting.render_direct_light(
            self.ctx, self.programs, frame.gbuffer, frame.shadows, material_lut,
            None if shares is None else shares.texture, prior, relight), "made_from": made_from})

    def _moved_since(self, frame, made_from) -> tuple | None:
        """(the G-buffer rectangle the moved triangles can cover, the depth atlas's last redraw cut to the texels it
        changed: shadows.changed_views) where an output made from `made_from` (its depth atlas's serial and
        generation, triangles and G-buffer key) was made one update of the same atlas ago, for the same camera; else
        None."""
        keys, maps, scene = frame.keys, frame.shadows.maps, frame.scene
        serial, generation, surfaces, gbuffer_key = made_from
        if maps.redrawn is None or (serial, generation + 1) != (maps.serial, maps.generation) \
                or gbuffer_key[1:] != keys["gbuffer"][1:]:
            return None
        box = sh.moved_box(surfaces, scene.surface_arrays())
        if box is False:
            return None
        w, h = frame.gbuffer.size
        return (0, 0, 0, 0) if box is None else gb.box_pixels(scene, w, h, box), sh.changed_views(maps)

    def _relight(self, frame) -> lighting.Relight | None:
        """After an object's move, the kept Diffuse Direct of the same camera, materials and shadow settings, lit
        from the same depth atlas one update ago, with where the move can change it (lighting.Relight); else None."""
        keys = frame.keys
        kept = self.cache.prior("direct_light", lambda k: k[0][1:] == keys["direct"][0][1:]
                                and k[1][4] == keys["shadow"][4])
        moved = None if kept is None else self._moved_since(frame, kept["made_from"])
        return None if moved is None else lighting.Relight(kept, *moved)

    def _sky_update(self, frame, k_sky) -> sky.SkyUpdate | None:
        """After an object's move, the kept sky shares of the same camera, shading and sky, made from the same depth
        atlas one update ago, and what the move redrew of the sky's maps (sky.SkyUpdate); else None."""
        kept = self.cache.prior("sky_visibility", lambda k: k[0][1:] == k_sky[0][1:] and k[1] == k_sky[1])
        moved = None if kept is None else self._moved_since(frame, kept.made_from)
        table = None if moved is None else sky.update_table(frame.shadows)
        return None if table is None else sky.SkyUpdate(kept, moved[0], table)

    @staticmethod
    def _method_output(frame):
        """The method's passes, or None: method "none", or a scene with no light at all (no lamp with power, no
        emission, a black world), whose indirect light is 0 without them (method_info says which)."""
        method = METHOD_PASSES.get(frame.settings.method)
        return method(frame) if method and not unlit(frame) else None

    def _direct_passes(self, scene: Scene, settings: RenderSettings, samples: sgb.Samples | None = None) -> FrameInputs:
        """The passes every method shares, up to the G-buffer and the shadow maps, and the keys they ran under.
        The G-buffer is the camera's, or with `samples` that of surface points (render_surface, render_points)."""
        ctx, programs, cache = self.ctx, self.programs, self.cache
        keys = {"geometry": hash_parts(*scene.surface_arrays()),
                **material_keys(scene), "lights": hash_parts(scene.lights),
                "camera": hash_parts(scene.camera, scene.pixel_aspect, settings.width, settings.height)
                if samples is None else samples.key,
                "world": hash_parts(scene.world)}
        geometry = cache.run("geometry", (keys["geometry"],), lambda: geo.upload_geometry(ctx, programs, scene))
        textures = cache.run("textures", (keys["materials"],), lambda: geo.upload_textures(ctx, scene))
        # Closed emitters trap their inner light unless the camera is inside one (common/emitters.py): the shells
        # depend on geometry and the materials' emission only, and the shadow maps on which of them hold the camera,
        # which changes only when the camera crosses one.
        shells = cache.run("emitter_shells", (keys["geometry"], keys["emission"]), lambda: em.sealed_shells(scene))
        camera = None if scene.camera is None else np.asarray(scene.camera.matrix_world, np.float64)[:3, 3]
        around = em.shells_around(scene, shells, camera)
        trapping = [s for k, s in enumerate(shells) if k not in around]
        keys["shadow"] = (keys["geometry"], keys["emission"], keys["lights"], keys["world"], repr(settings.shadow),
                         around)
        # The depth atlas is a pass of its own, keyed by the views it draws: a light's power or colour and the
        # world's change the records, not the maps (576 of them for the sky). A light's move redraws its own maps
        # into the kept atlas (direct/shadows.render_depth), not every light's; an object's move, in every map, the
        # rectangle its old and new places cover.
        shadows = cache.run("shadow_maps", keys["shadow"], lambda: sh.render_shadow_atlas(
            ctx, programs, scene, geometry, settings.shadow, trapping,
            depth_pass=lambda key, render: cache.run("shadow_depth", (keys["geometry"], key), lambda: render(
                cache.prior("shadow_depth", lambda k: True))),  # render_depth redraws what moved in it
            static_pass=lambda make: cache.run("light_sources", (lb.static_key(scene, trapping), keys["emission"],
                                                                 repr(settings.shadow), around), make)))
        keys["gbuffer"] = (keys["geometry"], keys["materials"], keys["camera"])
        if samples is None:
            gbuffer = cache.run("gbuffer", keys["gbuffer"], lambda: gb.render_gbuffer(
                ctx, programs, scene, geometry, textures, settings.width, settings.height))
        else:
            gbuffer = cache.run("gbuffer", keys["gbuffer"], lambda: sgb.upload_gbuffer(ctx, samples.arrays()))
        # Direct light reads the G-buffer's surfaces and shading, not a dielectric's base colour (material_keys).
        keys["direct"] = ((keys["geometry"], keys["shading"], keys["camera"]), keys["shadow"])
        return FrameInputs(ctx, programs, cache, scene, settings, geometry, textures, shadows, gbuffer, keys)

    def release(self) -> None:
        self.cache.clear()
        self.programs.release()
