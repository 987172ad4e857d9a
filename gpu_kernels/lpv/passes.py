# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's passes in the pipeline's pass cache (pipeline.METHOD_PASSES["lpv"]):

    rsm              ← shadow views, geometry, textures, RSM resolution (no material colour: lpv/rsm.glsl)
    geometry_volume  ← geometry, materials, grids
    lpv_inject       ← rsm, materials, grids
    lpv_propagate    ← injection, geometry volume, LPV settings (the transport: gather.gather_all or
                       propagate.propagate_all; with octree levels, octree.py's passes)
    lpv_lighting     ← gbuffer, transport

With the cached transport (transport = "transfer", lpv/transfer.py) the geometry volume is keyed by geometry
alone and the passes are instead:

    geometry_volume      ← geometry, grids                    (occupancy, normals, visibility planes)
    lpv_albedo           ← geometry volume, materials          (the surface voxels' albedo)
    lpv_transfer         ← geometry volume, budget             (clusters and the kernel T: the expensive part)
    lpv_transfer_albedo  ← transfer, albedo                    (M_ρ: cluster-to-cluster reflection, bounded)
    lpv_inject           ← rsm, transfer, materials            (the RSM's flux per cluster; first_bounce)
    lpv_propagate        ← all of the above, bounces           (the bounce series and one product with T)
    lpv_lighting         ← gbuffer, transport
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..common.method import MethodOutput
from ..voxel.voxelize import scene_area
from . import (clusters, gather, inject, lighting, occlusion, octree, propagate, receivers, rsm, transfer,
               transfer_update)
from .state import LpvGridState, cascade_grids

# Outputs kept per pass (gl/pass_cache.py): the geometry's passes for two settings (the live viewport's draft and
# final stages use two grids; each would otherwise rebuild its transfer on every edit).
KEEP = {name: 2 for name in ("geometry_volume", "lpv_albedo", "lpv_transfer", "lpv_transfer_albedo")}
# An orthographic RSM view (a sun's) needs no finer texels than this many per LPV cell: two per surface voxel
# (half a cell), into which its texels' flux is binned (lpv/rsm.view_resolution).
RSM_TEXELS_PER_CELL = 2


def run(frame) -> MethodOutput:
    """Run (or reuse) the LPV passes of one frame; `frame` is the pipeline's FrameInputs."""
    ctx, programs, cache, scene, s = frame.ctx, frame.programs, frame.cache, frame.scene, frame.settings.lpv
    grids = cascade_grids(scene, s)
    k_grids = tuple(g.key() for g in grids)
    texel = min(g.cell for g in grids) / RSM_TEXELS_PER_CELL
    # The RSMs hold positions, normals, texture colours and material indices: they follow the lights' views, not
    # their colours nor the materials' (lpv/rsm.glsl).
    k_rsm = (frame.keys["geometry"], frame.keys["textures"], frame.shadows.views_key, s.rsm_resolution, texel)
    # A light's move redraws its own views into the kept RSM of the same textures, an object's move the part of
    # every view it covers (render_rsm).
    prior = cache.prior("rsm", lambda k: k[1] == k_rsm[1] and k[3:] == k_rsm[3:])
    maps = cache.run("rsm", k_rsm, lambda: rsm.render_rsm(ctx, programs, scene, frame.geometry, frame.textures,
                                                           frame.shadows, s.rsm_resolution, texel, prior))
    budget = transfer_budget(scene, grids, s)
    if budget:
        return _transfer(frame, grids, k_grids, maps, k_rsm, budget)
    k_gv = (frame.keys["geometry"], frame.keys["materials"], k_grids, s.occlusion)
    gvs = cache.run("geometry_volume", k_gv, lambda: occlusion.geometry_volumes(
        ctx, programs, scene, frame.geometry, frame.textures, grids) if s.occlusion else [None] * len(grids))
    gather_vpls = s.gather_vpls if s.gathers else 0
    # the lights' and the materials' colours too
    k_inject = (k_rsm, frame.keys["shadow"], frame.keys["materials"], k_grids, s.rsm_downsample, gather_vpls)
    states = cache.run("lpv_inject", k_inject, lambda: inject.inject_all(
        ctx, programs, maps, frame.shadows, frame.textures, grids, s.rsm_downsample, gather_vpls))
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


def surface_voxels(scene, grids) -> float:
    """About how many fine voxels the scene's surfaces occupy: 1.5 per fine cell² of area (planes at an angle to
    the grid touch more than one voxel per cell)."""
    return 1.5 * scene_area(scene) / min(g.cell / 2 for g in grids) ** 2


def transfer_budget(scene, grids, s) -> int:
    """Clusters for the cached transport (LpvSettings: gather_vpls, more within transfer_pairs), or 0 where it does
    not apply or would not fit `transfer_mb` (T holds 2 × clusters × surface voxels float32). Not with cascades: a
    cascade's T would hold its own grid's clusters only, and its receivers miss the light of every surface outside
    it (a sphere's finest cascade got 0.43 of the coarse one's irradiance); the per-bounce gather draws each
    cascade's light from the whole scene's VPLs."""
    if s.transport != "transfer" or not s.gathers or len(grids) > 1:
        return 0
    voxels = max(surface_voxels(scene, grids), 1.0)
    wanted = max(s.gather_vpls, min(2 * s.gather_vpls, int(s.transfer_pairs / voxels)))  # see LpvSettings
    budget = min(wanted, int(s.transfer_mb * 2 ** 20 / (8 * voxels)))
    return budget if budget >= transfer.MIN_CLUSTERS else 0


def transfer_estimate(scene, s) -> dict:
    """What the cached transport would hold at these settings, from the surface area (no GPU work): surface voxels,
    clusters and MiB of T per cascade, or that it gathers instead."""
    grids = cascade_grids(scene, s)
    voxels = surface_voxels(scene, grids)
    budget = transfer_budget(scene, grids, s)
    return {"resolution": s.resolution, "surface_voxels": int(voxels), "clusters": budget,
            "mb": 8 * budget * voxels / 2 ** 20, "transport": "transfer" if budget else "gather"}


def transfer_bytes(scene, s) -> tuple[int, int]:
    """(GPU, host) bytes the cached transport adds at these settings, estimated from the surface area: the GPU's
    read-back buffer of T's rows (transfer.ROWS_BYTES), the sources and the receivers' light volumes (or, too large
    for those, their sparse index); T itself in host memory (2 × clusters × surface voxels float32)."""
    grids = cascade_grids(scene, s)
    budget = transfer_budget(scene, grids, s)
    if not budget:
        return 0, 0
    voxels = surface_voxels(scene, grids)
    light = sum(receivers.lookup_bytes(occlusion.fine_grid(g)) for g in grids)
    rows = min(transfer.ROWS_BYTES, 8 * budget * voxels)
    gpu = len(grids) * int(rows + budget * gather.VPL_DTYPE.itemsize) + light
    return gpu, len(grids) * int(8 * budget * voxels)


def _transfer(frame, grids, k_grids, maps, k_rsm, budget) -> MethodOutput:
    """The cached transport's passes (lpv/transfer.py); see the module docstring for what each reads."""
    ctx, programs, cache, scene, s = frame.ctx, frame.programs, frame.cache, frame.scene, frame.settings.lpv
    gvs, transfers, _, reflection, keys = _transfer_geometry(frame, grids, k_grids, budget)
    # Each light's first bounce per unit of its colour (colour-free key but for the materials' colours): a light's
    # colour, power or world edit only rescales them in the solve; from a kept one of the same RSMs, clusters and
    # material layers, a light's move re-bins that light and a material's colour edit adds its change (first_bounce).
    k_src = (k_rsm, keys["transfer"], frame.keys["layers"], frame.keys["materials"])
    prior = cache.prior("lpv_inject", lambda k: k[1:3] == k_src[1:3] and k[0][:2] == k_rsm[:2]
                        and k[0][3:] == k_rsm[3:])
    # After an object's move (new clusters: no prior), the records of the RSM's texels it left as they were are kept
    source = (maps, maps.generation, frame.keys["materials"], k_grids)
    kept = cache.prior("lpv_inject", lambda k: True)
    units = cache.run("lpv_inject", k_src, lambda: first_bounce(
        ctx, programs, maps, frame.shadows, frame.textures, transfers, grids, budget, prior, kept, source)).units
    colours = frame.shadows.buffers.lights["color_type"][:, :3].astype(np.float64)  # (lights, 3)
    k_prop = (k_src, frame.keys["shadow"], keys["albedo_transfer"], keys["gv"], s.max_iterations, s.clamp_negative,
              s.bounces, s.epsilon)
    solved = cache.run("lpv_propagate", k_prop, lambda: _solve(ctx, programs, gvs, grids, transfers, reflection, [
        (np.einsum("gck,gk->ck", first, colours), float((lost * colours).sum())) for first, lost in units], s))
    k_light = (frame.keys["gbuffer"], k_prop)
    indirect = cache.run("lpv_lighting", k_light,
                         lambda: lighting.lighting(ctx, programs, frame.gbuffer, solved["surfaces"], gvs, s))
    return MethodOutput(indirect, None, k_light, {"cascades": solved["stats"],
                                                  "skipped_work": skipped_work(solved["stats"], s)})


@dataclass
class FirstBounce:
    """Each light's first bounce per unit of its colour, binned into each cascade's clusters — (first (lights, C,
    3), lost (lights, 3)) per cascade — and what it was made from: each light's signature
    (direct/shadows.light_signatures) and the materials' base colours (direct/geometry.base_colors)."""
    units: list
    signatures: list
    colors: np.ndarray
    binned: int = 0  # lights binned when it was made (the others' rows came from the prior)
    recolored: int = 0  # materials whose colour edit was added to the prior's rows
    # (cascade, material) → that material's texels' first bounce per unit of its base colour (first, lost), for
    # these lights: a later colour edit of the same non-metal is that times the colour's change (recolor).
    bases: dict = field(default_factory=dict)
    # Per cascade the RSM's records and their slots (gather.rsm_records), and what they were made from: (the RSM
    # atlas, its generation, the materials' key, the grids' keys). None where the rows were updated per light.
    records: list = None
    source: tuple = None


MAX_BASES = 4  # materials whose FirstBounce.bases a pipeline keeps (the ones edited last)


def first_bounce(ctx, programs, maps, shadows, materials, transfers, grids, budget, prior=None, kept=None,
                 source=None) -> FirstBounce:
    """The RSMs' texels as VPL records (gather.rsm_records) binned per light into the clusters (clusters.bin_flux).
    With `prior` (made with the same RSMs, clusters and material layers), only the lights whose signature changed
    are binned again — a light's move costs that light's texels, not every light's; the others' rows are the
    prior's (a light's records and their order do not depend on the other lights) plus, where materials' colours
    changed, what the change adds (recolor) — a colour edit costs its material's texels once, then nothing.
    Without one, every record is binned, made again only where `kept` allows (texel_records); `source` is what
    they are made from (FirstBounce.source)."""
    signatures, colors = shadows.light_keys, materials.colors
    if prior is None or len(prior.signatures) != len(signatures) or prior.colors.shape != colors.shape:
        records = [texel_records(ctx, programs, maps, shadows, materials, grid, kept, k, source)
                   for k, grid in enumerate(grids)]
        units = [clusters.bin_flux(t.clusters, r[0], t.cells, t.normals, groups=len(signatures), axis=t.axis)
                 for t, r in zip(transfers, records)]
        return FirstBounce(units, signatures, colors, len(signatures), records=records, source=source)
    redo = np.array([a != b for a, b in zip(signatures, prior.signatures)], bool)
    recolored = np.any(prior.colors != colors, axis=1)
    out = FirstBounce([], signatures, colors, int(redo.sum()), int(recolored.sum()),
                      {} if redo.any() else dict(prior.bases))
    for k, (t, grid) in enumerate(zip(transfers, grids)):
        first, lost = prior.units[k]
        if redo.any():
            new = _bin(ctx, programs, maps, shadows, materials, t, grid, budget, len(signatures), lights=redo)
            first, lost = np.where(redo[:, None, None], new[0], first), np.where(redo[:, None], new[1], lost)
        if recolored.any() and not redo.all():
            bin_change = lambda change, lights: _bin(ctx, programs, maps, shadows, materials, t, grid, budget,
                                                     len(signatures), lights=lights, change=change)
            first, lost = recolor(first, lost, prior.colors, colors, ~redo, out.bases, k, bin_change)
        out.units.append((first, lost))
    while len(out.bases) > MAX_BASES * len(grids):
        out.bases.pop(next(iter(out.bases)))
    return out


def recolor(first, lost, old, new, lights, bases, cascade, bin_change) -> tuple:
    """`lights`' rows of (first, lost) with the materials whose base colours (rows of direct/geometry.base_colors)
    went from `old` to `new` recoloured. A non-metal's albedo is linear in its colour (c·D(μ) + a glossy part
    without it), so its change is (new − old) × its basis, the first bounce of its texels per unit colour, binned
    once into `bases` (by bin_change((new, old) colour rows, lights): all lights, from 0 to 1); a metal's change
    is binned as it is (Fresnel takes the colour)."""
    changed = np.any(old != new, axis=1)
    first, lost = np.array(first, np.float64), np.array(lost, np.float64)
    for m in np.nonzero(changed & (new[:, 3] == 0))[0]:
        key = (cascade, int(m))
        if key not in bases:
            unit, zero = np.zeros_like(new), np.zeros_like(new)
            unit[m, :3], zero[m, 3] = 1.0, 1.0
            bases[key] = bin_change((unit, zero), None)
        bases[key] = bases.pop(key)  # the latest edited last
        step = (new[m, :3] - old[m, :3]).astype(np.float64)
        first[lights] += bases[key][0][lights] * step
        lost[lights] += bases[key][1][lights] * step
    metals = changed & (new[:, 3] != 0)
    if metals.any():
        change = bin_change((new, np.column_stack([old[:, :3], metals])), lights)
        first, lost = first + change[0], lost + change[1]
    return first, lost


def texel_records(ctx, programs, maps, shadows, materials, grid, kept, cascade, source) -> tuple:
    """One cascade's RSM records and their slots (gather.rsm_records). From `kept`, a FirstBounce made from this RSM
    atlas as it was one update ago, with the same lights, materials and grids (`source`), only the blocks that
    update drew again are made again (gather.merge_records): an object's move costs the texels it covers in each
    view, not every light's texels — the same records, in the same order."""
    args = (ctx, programs, maps, shadows, materials, grid, 0, clusters.TEXEL_RECORDS)
    reusable = (isinstance(kept, FirstBounce) and kept.records is not None and source is not None
                and maps.redrawn is not None and kept.source[0] is maps and kept.source[1] + 1 == maps.generation
                and kept.source[2:] == source[2:] and kept.signatures == shadows.light_keys
                and np.array_equal(kept.colors, materials.colors))
    if not reusable:
        records, _, slots = gather.rsm_records(*args, unit_color=True, with_slots=True)
        return records, slots
    k = gather.block_size(maps, clusters.TEXEL_RECORDS)
    redone = gather.covered_blocks([maps.tiles[i] if rect is None else rect for i, rect in maps.redrawn], k,
                                   (-(-maps.size[0] // k), -(-maps.size[1] // k)))
    if not redone.any():  # nothing the RSM holds was drawn again (the triangles changed out of every view)
        return kept.records[cascade]
    records, _, slots = gather.rsm_records(*args, unit_color=True, blocks=redone, with_slots=True)
    return gather.merge_records(kept.records[cascade], (records, slots), redone)


def _bin(ctx, programs, maps, shadows, materials, t, grid, budget, groups, lights=None, change=None) -> tuple:
    """One cascade's records (gather.rsm_records: of `lights`, or the change of colours `change`) binned per light
    into its clusters: (first (groups, C, 3), lost (groups, 3))."""
    records = gather.rsm_records(ctx, programs, maps, shadows, materials, grid, budget, clusters.TEXEL_RECORDS,
                                 unit_color=True, lights=lights, change=change)[0]
    return clusters.bin_flux(t.clusters, records, t.cells, t.normals, groups=groups, axis=t.axis)


def _transfer_geometry(frame, grids, k_grids, budget) -> tuple:
    """The geometry's passes of the cached transport: geometry volume, albedo, T (updated from a kept T of the same
    grid after a geometry edit) and M_ρ; returns (gvs, transfers, albedo × area per cascade, M_ρ, their keys)."""
    ctx, programs, cache, scene, s = frame.ctx, frame.programs, frame.cache, frame.scene, frame.settings.lpv
    materials = frame.keys["materials"]
    k_gv = (frame.keys["geometry"], k_grids, "geometry only")

    def volumes():  # after an object's move, the region it changed voxelised into the kept voxelisation
        prior = cache.prior("geometry_volume", lambda key: key[1:] == k_gv[1:])
        gvs = receivers.axis_volumes(ctx, programs, scene, frame.geometry, frame.textures, grids, prior, materials)
        signature = receivers.albedo_signature(scene, frame.textures)
        for gv in gvs:  # the materials gv.surface_albedo was made with
            gv.materials_key, gv.material_signature = materials, signature
        return gvs
    gvs = cache.run("geometry_volume", k_gv, volumes)
    k_albedo = (k_gv, materials)
    albedo = cache.run("lpv_albedo", k_albedo, lambda: [receivers.current_albedo(
        ctx, programs, scene, frame.geometry, frame.textures, gv, materials) for gv in gvs])
    k_tr = (k_gv, budget, s.occlusion)
    # A kept T of the same grids (k_gv's grid keys), budget and occlusion, made before a geometry edit.
    priors = cache.prior("lpv_transfer", lambda key: key[1:] == k_tr[1:] and key[0][1] == k_gv[1]) or [None] * len(gvs)

    def build():  # written into the memory of the T this one evicts, where it fits (PassCache.spare)
        spares = list(cache.spare("lpv_transfer", besides=priors) or [])
        spares += [None] * (len(gvs) - len(spares))
        return [_build(ctx, programs, gv, grid, budget, s, p, getattr(spare, "matrix", None))
                for gv, grid, p, spare in zip(gvs, grids, priors, spares)]
    transfers = cache.run("lpv_transfer", k_tr, build)
    weights = [a * gv.surface_area[None, :, None] for a, gv in zip(albedo, gvs)]  # (2, R, 3) per side
    k_m = (k_tr, k_albedo)
    # M_ρ kept in float32: the bounce series reads it once a bounce, and in float64 a light's move spent 19 ms of
    # its 150 reading it (default_principled, 979 clusters); the series' sums stay in float64 (transfer.solve).
    reflection = cache.run("lpv_transfer_albedo", k_m, lambda: [
        (m.astype(np.float32), gain) for m, gain in (transfer.bounded_transport(t, transfer.albedo_transfer(t, w), w)
                                                     for t, w in zip(transfers, weights))])
    return gvs, transfers, weights, reflection, {"gv": k_gv, "transfer": k_tr, "albedo_transfer": k_m}


def skipped_work(stats: list, s) -> list:
    """What the scene let the cached transport leave out, in words (render --json "skipped_work", the panel)."""
    out = []
    for c in stats[:1]:  # the cascades skip alike
        if c["injected_flux"] == 0:
            out.append("first bounce: no light reaches a surface the transport sees (no lights, or all off)")
        elif c["bounces_used"] < s.bounces:
            out.append(f"bounces {c['bounces_used'] + 1}-{s.bounces}: the series stopped after {c['bounces_used']} "
                       f"(a bounce added less than epsilon = {s.epsilon:g} of the largest)")
    return out


def _build(ctx, programs, gv, grid, budget, s, prior=None, spare=None) -> transfer.Transfer:
    """Clusters and T of one cascade: updated from `prior` (the same grid before a geometry edit) where that
    re-evaluates less than transfer_update.REBUILD_SHARE of T, else made anew with the budget re-checked against the
    real surface-voxel count (an update past it builds anew too); T in `spare`'s memory where it fits
    (transfer.empty_matrix)."""
    fits = int(s.transfer_mb * 2 ** 20 / (8 * max(gv.surface_count, 1)))  # clusters whose T fits transfer_mb
    updated = transfer_update.update_transfer(ctx, programs, gv, grid, s.occlusion, prior, spare=spare,
                                              most_clusters=fits) if prior is not None and prior.grid == grid else None
    if updated is not None:
        return updated
    sources = clusters.make_clusters(gv.cells, gv.surface_normal, gv.surface_area, gv.fine,
                                     max(transfer.MIN_CLUSTERS, min(budget, fits)), positions=gv.positions,
                                     bounds=gv.bounds)
    matrix = transfer.build_transfer(ctx, programs, gv, grid, sources, s.occlusion)
    return transfer.sort_by_cluster(sources, matrix, gv, grid, spare, most=2 * fits * int(gv.surface_count))


def _solve(ctx, programs, gvs, grids, transfers, reflection, sources, s) -> dict:
    """Each cascade's bounce series (transfer.solve), uploaded for the flux lookup, and its statistics."""
    sides, stats = [], []
    for gv, grid, t, (m, gain), (first, unbinned) in zip(gvs, grids, transfers, reflection, sources):
        irradiance, passes = transfer.solve(t, m, first, s.bounces, s.epsilon, gain)
        sides.append(irradiance)
        stats.append({"cells": list(grid.size), "cell": grid.cell, "transport": "transfer",
                      "clusters": t.clusters.count, "block": t.clusters.block, "transfer_mb": t.nbytes / 2 ** 20,
                      "transfer_updated": t.updated, "voxelised": gv.voxelised,
                      "kept_voxels_mb": gv.voxels.nbytes / 2 ** 20, "injected_flux": float(first.sum()),
                      "escaped_flux": unbinned,
                      "bounces": [{"flux": f} for f in passes], "bounces_used": len(passes)})
    return {"surfaces": receivers.upload_light(ctx, programs, grids, gvs, sides), "stats": stats}
