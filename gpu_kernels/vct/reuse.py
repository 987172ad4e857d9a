# SPDX-License-Identifier: GPL-3.0-or-later
"""The per-pixel diffuse gathers of the last view reused after a camera move (reverse reprojection caching, Nehab
et al. 2007, "Accelerating real-time shading with reverse reprojection caching").

Bounced light does not depend on the camera: with the volumes, the trace settings and the geometry unchanged, the
gather at a surface point is the same from any view. So a camera move traces only the samples (vct/trace.glsl's
reduced-resolution texels) whose point the last view had no gather on: vct/reuse.glsl projects each sample into
the last view and takes the value of a last sample on the same surface (normals within NORMAL_COS, each point
within PLANE_VOXELS of a voxel from the other's tangent plane) whose traced point this view sees within
`VctSettings.reuse_reach` texels of the sample; the rest are marked and traced (vct/trace.glsl MODE_MARKED). Every
sample keeps the point its value was traced at (its origin), so a value reused over many moves stays within that
reach: the image never drifts. The measured difference from a full trace: benchmarks/results/vct_llvmpipe.md.

Not while accumulating (every frame turns the cones), and not on the viewport's surface atlas (no camera). A light,
world or material edit changes the volumes, so the next trace starts over (and records its hits, vct/replay.py).
"""
from __future__ import annotations

import numpy as np

from ..gl.bind import bind_named, dispatch_counted, set_uniforms, write_uniform
from .settings import VctSettings
from .trace import marked_list, trace, trace_marked, traced_size

NORMAL_COS = 0.999  # 2.6°: a curved surface's samples a texel apart differ by more unless it is gently curved
PLANE_VOXELS = 0.05  # of a voxel: two surfaces closer than that share every voxel their cones read


def enabled(gbuffer, s: VctSettings) -> bool:
    """Whether traces of this G-buffer keep what a later view may reuse: a camera's view, a reach, no accumulation."""
    return s.reuse_reach > 0 and s.temporal_frames <= 1 and gbuffer.view_projection is not None


def last_view(cache, key: tuple, gbuffer, s: VctSettings) -> dict | None:
    """The kept vct_trace output whose gathers a trace keyed `key` (((gbuffer, bounce, trace settings), frame))
    may take: another camera view of the same volumes, trace settings and accumulation frame, or None."""
    if not enabled(gbuffer, s):
        return None
    (_, volumes, settings), frame = key

    def same_light(k):
        return k != key and k[0][1:] == (volumes, settings) and k[1] == frame
    last = cache.prior("vct_trace", same_light)
    return last if last is not None and "origin" in last else None


def trace_view(ctx, programs, gbuffer, faces, volumes, s: VctSettings, rotation_deg, hits, last: dict | None) -> dict:
    """vct_trace's output for this view: the samples reused from `last` (last_view) and the others traced, or,
    with no last view, the full trace (recording or replaying `hits`); with the samples' origins for the next view
    and the count of reused samples (the plain trace where reuse is not enabled)."""
    if not enabled(gbuffer, s):
        return trace(ctx, programs, gbuffer, faces, volumes, s, rotation_deg, hits)
    out = _reproject(ctx, programs, gbuffer, s, last, volumes.grid.cell)
    if last is None:
        traced = trace(ctx, programs, gbuffer, faces, volumes, s, rotation_deg, hits, out=out["indirect"])
    else:
        trace_marked(ctx, programs, gbuffer, faces, volumes, s, out["indirect"], s.indirect_scale, out["listed"],
                     out["retraced"], rotation_deg)
        traced = {"indirect": out["indirect"], "scale": int(s.indirect_scale), "replayed": False}
    out.pop("listed").release()
    return {**out, **traced}


def _reproject(ctx, programs, gbuffer, s: VctSettings, last: dict | None, cell: float) -> dict:
    """vct/reuse.glsl: the traced texture (reused values, the rest marked), the samples' origins and normals."""
    size = traced_size(gbuffer, s)
    textures = {name: ctx.texture(size, 4, dtype="f4") for name in ("indirect", "origin", "origin_normal")}
    prog = programs.compute("vct/reuse.glsl", {"MODE_SEED": None} if last is None else None)
    unit = bind_named(prog, [("u_position", gbuffer.textures["position"]), ("u_normal", gbuffer.textures["normal"])])
    set_uniforms(prog, {"u_image_size": size, "u_full_size": tuple(int(n) for n in gbuffer.size),
                        "u_scale": int(s.indirect_scale)})
    write_uniform(prog, "u_view_projection", np.asarray(gbuffer.view_projection).T)
    if last is not None:
        bind_named(prog, [("u_last", last["indirect"]), ("u_last_origin", last["origin"]),
                          ("u_last_normal", last["origin_normal"])], unit)
        set_uniforms(prog, {"u_last_size": tuple(last["indirect"].size), "u_last_full_size": last["full_size"],
                            "u_reach": float(s.reuse_reach), "u_plane": float(PLANE_VOXELS * cell),
                            "u_normal_cos": NORMAL_COS})
        write_uniform(prog, "u_last_view_projection", np.asarray(last["view_projection"]).T)
    for i, name in enumerate(("indirect", "origin", "origin_normal")):
        textures[name].bind_to_image(i, read=False, write=True)
    listed = marked_list(ctx, size)
    listed.bind_to_storage_buffer(5)
    marked, reused = dispatch_counted(ctx, prog, size, counts=2)
    return {**textures, "view_projection": gbuffer.view_projection, "full_size": tuple(int(n) for n in gbuffer.size),
            "reused": reused, "retraced": marked, "listed": listed}
