# SPDX-License-Identifier: GPL-3.0-or-later
"""The VCT's passes in the pipeline's pass cache (pipeline.METHOD_PASSES["vct"]):

    vct_voxelize    ← geometry, grid: the surfaces' areas and normals
    vct_albedo      ← voxels, materials: each voxel face's albedo (vct/inject.face_albedo), apart from its light
    vct_geometry    ← geometry, emission, grid, levels: what the passes below derive from the geometry alone, made
                      by the first that needs each part and kept across light, world and material colour edits
                      (volumes.VoxelGeometry)
    vct_inject_lamps, _emitters, _sky
                    ← voxels, that part's lights' shadow maps and records per unit of its largest colour: the light
                      arriving at each face per unit albedo (vct/parts.py); vct_inject_all instead, every light at
                      once (per unit of the largest colour, vct/colours.py), where several parts' volumes would not
                      fit
    vct_inject      ← the parts and their weights, summed and multiplied by the faces' albedo
    vct_mipmap      ← injection, anisotropy
    vct_bounce      ← mipmaps, cone settings, bounces
    vct_specular    ← gbuffer, bounced volumes, specular settings
    vct_hits        ← geometry, camera, emission, grid, trace settings: the per-pixel trace's hits
                      (vct/replay.py), filled by the first vct_trace and replayed by the next ones (a light,
                      world or material colour edit)
    vct_trace       ← gbuffer, bounced volumes, trace settings, accumulation frame; after a camera move, the
                      last view's vct_trace, whose gathers it reuses where they lie on its samples' surfaces
                      (vct/reuse.py)
    vct_upsample    ← vct_trace (indirect_scale > 1)
    vct_accumulate  ← the upsampled trace (temporal_frames > 1)
    vct_scale       ← the results, the largest light colour (scaled back to the lights' own colours)
"""
from __future__ import annotations

import numpy as np

from ..common.method import MethodOutput
from . import bounce, colours, inject, mipmap, parts, replay, reuse, specular, temporal, trace, upsample
from .volumes import VoxelGeometry, mip_levels, vct_grid, voxelize_scene

# Outputs kept per pass (gl/pass_cache.py): the voxels, what their geometry decides and the per-pixel hits of two
# grids and G-buffers (the live viewport's draft and final stages, which alternate after every edit).
KEEP = {"vct_voxelize": 2, "vct_albedo": 2, "vct_geometry": 2, "vct_hits": 2}


def run(frame) -> MethodOutput:
    """Run (or reuse) the VCT passes of one frame; `frame` is the pipeline's FrameInputs. The output's indirect
    texture holds Diffuse Indirect and, in alpha, the voxel AO."""
    ctx, programs, cache, scene, s = frame.ctx, frame.programs, frame.cache, frame.scene, frame.settings.vct
    grid = vct_grid(scene, s)
    levels = mip_levels(s.resolution)
    k_vox = (frame.keys["geometry"], grid.key())
    vox = cache.run("vct_voxelize", k_vox,
                    lambda: voxelize_scene(ctx, programs, scene, frame.geometry, frame.textures, grid))
    shared = cache.run("vct_geometry", (frame.keys["geometry"], frame.keys["emission"], grid.key(), levels),
                       VoxelGeometry)
    # The lights per unit of the largest colour (vct/colours.py): an edit scaling every light alike keeps all that
    # follows, and only the results are scaled back.
    scale = colours.colour_scale(frame.shadows)
    scratch = {}  # the front-most surfaces (and the light's accumulator) shared by this frame's albedo and injections
    try:
        k_albedo = (k_vox, frame.keys["materials"])
        albedo = cache.run("vct_albedo", k_albedo, lambda: inject.face_albedo(
            ctx, programs, scene, frame.geometry, frame.textures, vox, scratch))
        faces, k_inject = _inject(frame, vox, shared, (k_vox, levels, albedo, k_albedo), scale, scratch)
    finally:
        inject.release_scratch(scratch)
    k_mip = (k_inject, s.anisotropic)
    volumes = cache.run("vct_mipmap", k_mip, lambda: mipmap.build_volumes(ctx, programs, faces, s.anisotropic,
                                                                         shared=shared))
    k_bounce = (k_mip, s.key("bounce"))
    bounced = cache.run("vct_bounce", k_bounce,
                        lambda: bounce.bounce(ctx, programs, albedo, faces, volumes, s, shared))
    k_spec = (frame.keys["gbuffer"], k_bounce, s.key("specular"))
    glossy = cache.run("vct_specular", k_spec, lambda: specular.specular(ctx, programs, frame.gbuffer, faces,
                                                                         bounced, s))
    indirect, k_trace, extra = _per_pixel(frame, faces, bounced, (frame.keys["gbuffer"], k_bounce,
                                                                          s.key("trace")), (grid.key(), levels))
    info = {**trace.render_info(faces, bounced, s), "specular_pixels": glossy["traced"], **extra,
            **replay.stats(shared.gather_pool, "gather_steps"),
            "skipped_work": bounce.skipped_work(bounced.bounce_stats or [], s) + specular.skipped_work(glossy, s)}
    key, out = (k_trace, k_spec), (indirect, glossy["glossy"])
    if np.any(scale != 1.0):
        key = (k_trace, k_spec, scale.tobytes())
        out = cache.run("vct_scale", key, lambda: colours.scale_output(ctx, list(out), scale))
    return MethodOutput(*out, key, colours.scale_info(info, scale), has_ao=True)


def pass_seconds(timings: dict, name: str) -> float:
    """A render's seconds in pass `name` (RenderResult.timings), vct_inject with the parts it sums
    (vct_inject_lamps, _emitters, _sky, _all): the benchmarks' per-pass tables."""
    names = [name] + ([f"{name}_{p}" for p in parts.PARTS + (parts.ALL,)] if name == "vct_inject" else [])
    return sum(timings.get(n, 0.0) for n in names)


def _inject(frame, vox, shared, base: tuple, scale: np.ndarray, scratch: dict) -> tuple:
    """vct_inject: each part of the lights (the lamps, the emissive meshes, the sky; or every light at once where
    their volumes would not fit, vct_inject_all) injected in its own pass per unit of its colour and albedo, summed
    with weights back to the transport's unit `scale` and multiplied by the faces' albedo (vct/parts.py). `base` =
    (the voxels' key, levels, the faces' albedo, its key); `scratch` as vct/inject.inject's. Returns the faces and
    their key."""
    ctx, programs, cache, shadows = frame.ctx, frame.programs, frame.cache, frame.shadows
    k_vox, levels, albedo, k_albedo = base

    def injected(subset):
        return colours.with_records(ctx, shadows, subset, lambda sh: inject.inject(
            ctx, programs, frame.scene, frame.geometry, frame.textures, vox, sh, levels, shared, scratch))

    injected_parts = parts.injected_parts(shadows, vox.grid)
    made, keys = [], []
    for part in injected_parts:
        subset = colours.unit_records(shadows, part.scale, part.lights)
        key = (k_vox, parts.part_key(shadows, part, subset), levels)
        made.append(cache.run(f"vct_inject_{part.name}", key, lambda subset=subset: injected(subset)))
        keys.append(key)
    cache.drop([f"vct_inject_{name}" for name in set(parts.PARTS + (parts.ALL,)) - {p.name for p in injected_parts}])
    weights = [part.scale / scale for part in injected_parts]
    k_inject = (tuple(keys), np.asarray(weights, np.float32).tobytes(), k_albedo)
    return cache.run("vct_inject", k_inject, lambda: parts.sum_parts(ctx, programs, made, weights, albedo,
                                                                       shared.centroids)), k_inject


def _per_pixel(frame, faces, bounced, base, grid):
    """The per-pixel cones: trace, upsample (indirect_scale > 1), temporal accumulation (temporal_frames > 1).
    The trace's inputs (`base`) key the history; while it holds fewer than temporal_frames frames, the frame
    index makes the keys new, so trace (and upsample) run again with the next jitter. The trace records its hits
    and replays them while what they depend on holds (vct_hits: the geometry, camera and traced size, `grid` = the
    grid's key and levels, the trace settings; and the emission, which decides which emitters are closed shells,
    common/emitters.py); not while accumulating, where every frame turns the cones. Returns (texture, the
    trace's key, the upsampling's and accumulation's statistics)."""
    ctx, programs, cache, s, gbuffer = frame.ctx, frame.programs, frame.cache, frame.settings.vct, frame.gbuffer
    accumulating = s.temporal_frames > 1
    prior = cache.entries.get("vct_accumulate")
    index = temporal.frame_index(prior.value if prior and accumulating else None, base, s.temporal_frames)
    rotation = temporal.jitter_deg(s, index) if accumulating else s.cone_rotation
    k_trace = (base, index)
    hits, last = None, reuse.last_view(cache, k_trace, gbuffer, s)
    if s.anisotropic and not accumulating and last is None:
        size = trace.traced_size(gbuffer, s)
        k_hits = tuple(frame.keys[k] for k in ("geometry", "camera", "emission")) + (size, grid, s.key("trace"))
        if cache.prior("vct_trace", lambda k: k == k_trace) is not None:  # kept: its pool, if it recorded one
            hits = cache.prior("vct_hits", lambda k: k == k_hits)
        else:  # sized from the last record with the same cones (the viewport's draft stage traces fewer)
            prior = next((v for k, v in cache.kept("vct_hits") if k[-1] == k_hits[-1]), None)
            hits = cache.run("vct_hits", k_hits, lambda: replay.allocate(ctx, size, prior))
    traced = cache.run("vct_trace", k_trace, lambda: reuse.trace_view(ctx, programs, gbuffer, faces, bounced, s,
                                                                      rotation, hits, last))
    info = {**replay.stats(hits), "reused_texels": traced.get("reused", 0)}
    indirect = traced["indirect"]
    if s.indirect_scale > 1:
        up = cache.run("vct_upsample", k_trace, lambda: upsample.upsample(
            ctx, programs, gbuffer, traced, faces, bounced, s, rotation))
        indirect, info["fixup_pixels"] = up["indirect"], up["fixup"]
    if accumulating:
        history = cache.run("vct_accumulate", k_trace, lambda: temporal.accumulate(
            ctx, programs, prior.value if prior else None, indirect, base, index))
        indirect = history.texture
        info["temporal"] = {"frames": history.frames, "of": s.temporal_frames,
                            "done": history.frames >= s.temporal_frames}
    return indirect, k_trace, info
