# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's passes in the pipeline's pass cache (pipeline.METHOD_PASSES["lpv"]):

    rsm              ← shadow views, RSM resolution
    geometry_volume  ← geometry, materials, grids
    lpv_inject       ← rsm, grids, geometry volume, world
    lpv_propagate    ← injection, geometry volume, LPV settings (the transport: gather.gather_all or
                       propagate.propagate_all; with octree levels, octree.py's passes)
    lpv_lighting     ← gbuffer, transport
"""
from __future__ import annotations

from ..common.method import MethodOutput
from ..scene import hash_parts
from . import gather, inject, lighting, occlusion, octree, propagate, rsm
from .state import cascade_grids


def run(frame) -> MethodOutput:
    """Run (or reuse) the LPV passes of one frame; `frame` is the pipeline's FrameInputs."""
    ctx, programs, cache, scene, s = frame.ctx, frame.programs, frame.cache, frame.scene, frame.settings.lpv
    grids = cascade_grids(scene, s)
    k_grids = tuple(g.key() for g in grids)
    k_rsm = (frame.keys["shadow"], s.rsm_resolution)
    maps = cache.run("rsm", k_rsm, lambda: rsm.render_rsm(ctx, programs, scene, frame.geometry, frame.textures,
                                                           frame.shadows, s.rsm_resolution))
    k_gv = (frame.keys["geometry"], frame.keys["materials"], k_grids, s.occlusion)
    gvs = cache.run("geometry_volume", k_gv, lambda: occlusion.geometry_volumes(
        ctx, programs, scene, frame.geometry, frame.textures, grids) if s.occlusion else [None] * len(grids))
    gather_vpls = s.gather_vpls if s.gathers else 0
    k_inject = (k_rsm, k_grids, k_gv, hash_parts(scene.world), s.rsm_downsample, gather_vpls)
    states = cache.run("lpv_inject", k_inject, lambda: inject.inject_all(
        ctx, programs, maps, frame.shadows, grids, scene.world.color, gvs, s.rsm_downsample, gather_vpls))
    k_prop = (k_inject, k_gv, repr(s))
    if s.octree_levels:
        states, gvs, stats, s = _octree(frame, states, gvs, grids, k_gv, k_inject, k_prop)
    else:
        transport = gather.gather_all if s.gathers else propagate.propagate_all
        stats = cache.run("lpv_propagate", k_prop, lambda: transport(ctx, programs, states, gvs, s))
    k_light = (frame.keys["gbuffer"], k_prop)
    indirect = cache.run("lpv_lighting", k_light,
                         lambda: lighting.lighting(ctx, programs, frame.gbuffer, states, gvs, s))
    return MethodOutput(indirect, None, k_light, stats)


def _octree(frame, states, gvs, grids, k_gv, k_inject, k_prop):
    """The octree LPV's passes (Olovsson and Doggett 2013: index volume, downsample, per-level propagation,
    merge); returns the merged state as the one cascade the lookup reads, and the lookup's settings."""
    ctx, programs, cache, s = frame.ctx, frame.programs, frame.cache, frame.settings.lpv
    geo = cache.run("lpv_octree_geometry", (k_gv, s.octree_levels),
                    lambda: octree.build_geometry(ctx, gvs[0], grids[0], s.octree_levels))
    tree = cache.run("lpv_downsample", (k_inject, s.octree_levels),
                     lambda: octree.downsample(ctx, programs, states[0], geo))
    stats = cache.run("lpv_propagate", k_prop, lambda: octree.propagate_levels(ctx, programs, tree, geo, s))
    merged = cache.run("lpv_merge", k_prop, lambda: octree.merge(ctx, programs, tree, geo))
    return [merged], [None], stats, octree.lookup_settings(s)
