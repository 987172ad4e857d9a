# SPDX-License-Identifier: GPL-3.0-or-later
"""vct_bounce: bounces − 1 gathers at the voxel faces, each followed by a re-mip, and the rest of the bounces
extrapolated as a geometric series (common/bounce_tail.py), re-mipped once after it (not also after the last
gather: no cone reads those volumes)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..common.bounce_tail import tail_ratio, tail_sum
from ..gl.bind import VOLUME_GROUP, bind_samplers, dispatch, dispatch_counted, set_uniform, texture3d
from . import replay
from .inject import face_flux
from .mipmap import build_volumes
from .settings import VctSettings
from .trace import bind_cones
from .volumes import ConeVolumes, FaceAlbedo, Faces, VoxelGeometry, bind_volumes, gather_levels


def bounce(ctx, programs, albedo: FaceAlbedo, direct_faces: Faces, volumes: ConeVolumes, s: VctSettings,
           shared: VoxelGeometry | None = None) -> ConeVolumes:
    """bounces − 1 gathers at the voxel faces (vct/bounce.glsl), each followed by a re-mip (where a tail follows the
    last gather, after the tail instead). Returns the volumes
    the final gather reads (a non-owning view of `volumes` when bounces = 1); `bounce_stats` lists the flux the
    faces carry after each bounce (bounce 1 = direct light reflected once). The list of faces to gather is taken
    from `shared` where it holds one, else made and left there."""
    stats = [{"bounce": 1, "flux": direct_faces.flux}]
    gathered = s.bounces if not s.gathered_bounces else min(s.gathered_bounces, s.bounces)
    if gathered <= 1 or _total(stats[0]) <= 0.0:  # one bounce, or no light reached a voxel: nothing to gather
        return ConeVolumes(volumes.textures, volumes.grid, volumes.levels, volumes.anisotropic, owned=False,
                           bounce_stats=stats, layers=volumes.layers, layers_owned=False)
    grid = direct_faces.grid
    faces = Faces([texture3d(ctx, grid.size, zero=True) for _ in range(6)], grid, direct_faces.levels)
    if shared is not None and shared.face_list is None:
        shared.face_list = face_list(ctx, programs, direct_faces)
    listed, count = shared.face_list if shared is not None else face_list(ctx, programs, direct_faces)
    pool = gather_pool(ctx, shared, count, s) if shared is not None and volumes.anisotropic else None
    own, source, previous = None, volumes, None
    for b in range(2, gathered + 1):
        if b == gathered and gathered < s.bounces:  # the tail needs the last increment L_K − L_(K−1): keep L_(K−1)
            previous = faces if b > 2 else direct_faces
            if b > 2:
                faces = Faces([texture3d(ctx, grid.size, zero=True) for _ in range(6)], grid, direct_faces.levels)
        prog = gather_program(programs, source, direct_faces, albedo, s, pool)
        for i, t in enumerate(faces.textures):
            t.bind_to_image(i, read=False, write=True)
        gather_listed(ctx, prog, listed, count, pool)
        stats.append({"bounce": b, "flux": face_flux(ctx, programs, faces)[0]})
        stopped = _total(stats[-1]) - _total(stats[-2]) < s.epsilon * _total(stats[0])
        if stopped or b < gathered or gathered == s.bounces:  # else the tail follows, and the re-mip after it
            own = source = build_volumes(ctx, programs, faces, volumes.anisotropic, into=own, layers=volumes.layers)
        if stopped:
            stats[-1]["stopped"] = True  # the series ends here: no further gather, no tail
            break
    if shared is None:
        listed.release()
    if previous is not None and stats[-1].get("stopped"):
        if previous is not direct_faces:
            previous.release()
    elif previous is not None:
        stats.append(extrapolate_tail(ctx, programs, faces, previous, stats, s.bounces))
        if previous is not direct_faces:
            previous.release()
        own = build_volumes(ctx, programs, faces, volumes.anisotropic, into=own, layers=volumes.layers)
    own.faces, own.bounce_stats = faces, stats
    return own


FACES_PER_DISPATCH = 65535 * 64  # work groups of 64 (vct/bounce.glsl), at most 65535 a dispatch
# Entries of the face list reordered together after the record (order_by_steps): measured on the Cornell box, the
# replays took about as long with runs of 64 to 4096 entries, a third longer sorted over the whole list.
ORDER_BLOCK = 256


def face_list(ctx, programs, faces: Faces, capacity: int | None = None) -> tuple:
    """The faces of `faces` with coverage, (voxel, face) as ivec4 in a storage buffer (vct/bounce.glsl MODE_LIST),
    and how many; room for `capacity` (default six per occupied voxel, Faces.occupied), made again larger where
    more were counted."""
    capacity = max(6 * int(faces.occupied) if capacity is None else capacity, 1)
    listed = ctx.buffer(reserve=16 * capacity)
    prog = programs.compute("vct/bounce.glsl", {"MODE_LIST": None})
    bind_samplers(prog, "u_direct", faces.textures, 0)
    set_uniform(prog, "u_grid_size", tuple(int(n) for n in faces.grid.size))
    set_uniform(prog, "u_capacity", capacity)
    listed.bind_to_storage_buffer(5)
    count = dispatch_counted(ctx, prog, faces.grid.size, VOLUME_GROUP)
    if count > capacity:
        listed.release()
        return face_list(ctx, programs, faces, count)
    # The atomic counter lists the faces in an order that changes from run to run: sorted (by face direction, then
    # voxel), every run groups the same faces into SIMD groups, whose cones then point alike (measured: as fast).
    entries = np.frombuffer(listed.read(size=16 * count), np.int32).reshape(count, 4)
    entries = entries[np.lexsort((entries[:, 0], entries[:, 1], entries[:, 2], entries[:, 3]))]
    listed.write(np.ascontiguousarray(entries).tobytes())
    return listed, count


def gather_program(programs, source: ConeVolumes, direct_faces: Faces, albedo: FaceAlbedo, s: VctSettings,
                   pool=None):
    """vct/bounce.glsl's gathers from `source`, each face reflecting with its `albedo`, bound (MODE_RECORD_GATHER /
    MODE_REPLAY_GATHER with a `pool`)."""
    defines = {"MODE_ANISO": None} if source.anisotropic else {}
    if pool is not None:
        defines["MODE_REPLAY_GATHER" if pool.recorded else "MODE_RECORD_GATHER"] = None
    prog = programs.compute("vct/bounce.glsl", defines or None)
    unit = bind_volumes(prog, source, 0)
    unit = bind_samplers(prog, "u_direct", direct_faces.textures, unit)
    unit = bind_samplers(prog, "u_centroid", direct_faces.centroids, unit)
    bind_samplers(prog, "u_albedo", albedo.textures, unit)
    bind_cones(prog, source.grid, min(source.levels, gather_levels(s.resolution)),
               replace(s, diffuse_cones=s.bounce_cones or s.diffuse_cones))
    return prog


def gather_pool(ctx, shared: VoxelGeometry, count: int, s: VctSettings) -> replay.HitPool:
    """The gathers' steps kept with the geometry's parts (vct/hits.glsl GatherStep): the one made under the same
    cone settings, or a new, empty one (the next gather records into it)."""
    key = (count, s.key("bounce"))
    if shared.gather_pool is None or shared.gather_pool.key != key:
        if shared.gather_pool is not None:
            shared.gather_pool.release()
        shared.gather_pool = replay.allocate(ctx, (count,), slots=replay.GATHER_SLOTS,
                                             per_item=replay.CHUNKS_PER_FACE)
        shared.gather_pool.key = key
    return shared.gather_pool


def gather_listed(ctx, prog, listed, count: int, pool: replay.HitPool | None = None) -> None:
    """vct/bounce.glsl over the `count` faces of `listed` (face_list), one per invocation; with a `pool`, recorded
    into it (and marked recorded) or replayed from it."""
    recording = pool is not None and not pool.recorded
    listed.bind_to_storage_buffer(5)
    set_uniform(prog, "u_face_count", count)
    with replay.pooled(ctx, prog, pool):
        for first in range(0, count, FACES_PER_DISPATCH):
            set_uniform(prog, "u_face_first", first)
            dispatch(prog, (min(FACES_PER_DISPATCH, count - first),), 64)
        ctx.memory_barrier()
    if recording:
        order_by_steps(listed, pool, count)


def order_by_steps(listed, pool: replay.HitPool, count: int) -> None:
    """The face list and the pool's headers (one per list entry) reordered within each run of ORDER_BLOCK entries,
    most recorded steps first. A replay loops over a face's steps, and SIMD lanes run as many iterations as their
    longest face: in the list's order (by face direction, then voxel) the lanes of a group of 8 ran 1.4× the steps
    they replayed, 1.55× in groups of 16 (the Cornell box and window_room). Sorted over the whole list, a group's
    faces lay all over the grid and the replays got slower; within runs, they stay near each other. Each face's
    result is its own, so the order changes no value."""
    headers = np.frombuffer(pool.headers.read(size=16 * count), np.uint32).reshape(count, 4)
    entries = np.frombuffer(listed.read(size=16 * count), np.int32).reshape(count, 4)
    order = np.lexsort((-headers[:, 1].astype(np.int64), np.arange(count) // ORDER_BLOCK))
    pool.headers.write(np.ascontiguousarray(headers[order]).tobytes())
    listed.write(np.ascontiguousarray(entries[order]).tobytes())


def _total(stat: dict) -> float:
    """A bounce statistics row's flux, summed over RGB."""
    return float(np.sum(stat["flux"]))


def skipped_work(stats: list, s: VctSettings) -> list:
    """What the scene let the bounce series leave out, in words (render --json "skipped_work", the panel)."""
    if stats and _total(stats[0]) <= 0.0:
        return ["bounces: no light reaches a voxel (no lights, or all off)"]
    if stats and stats[-1].get("stopped") and stats[-1]["bounce"] < s.bounces:
        b = stats[-1]["bounce"]
        return [f"bounces {b + 1}-{s.bounces}: the series stopped after {b} (a bounce added less than epsilon = "
                f"{s.epsilon:g} of the first)"]
    return []


def extrapolate_tail(ctx, programs, faces: Faces, previous: Faces, stats: list, bounces: int) -> dict:
    """Bounces K+1 … N without gathering them (common/bounce_tail.py): with B_k the flux bounce k added (B_1 =
    the direct light's reflection), the faces get L_N = L_K + (L_K − L_(K−1)) · Σ_{j=1}^{N−K} r^j, in place on the
    GPU (vct/bounce_tail.glsl). Coverage α is kept. Returns the statistics row of the tail."""
    k = len(stats)  # bounces gathered so far (stats[i] = after bounce i + 1)
    flux = [np.asarray(st["flux"], np.float64) for st in stats]
    added = [flux[0]] + [flux[i] - flux[i - 1] for i in range(1, k)]
    ratio = tail_ratio(added[-1], added[-2])
    tail = tail_sum(ratio, bounces - k)
    prog = programs.compute("vct/bounce_tail.glsl")
    set_uniform(prog, "u_grid_size", tuple(int(v) for v in faces.grid.size))
    set_uniform(prog, "u_tail", tuple(float(v) for v in tail))
    for current, prev in zip(faces.textures, previous.textures):
        bind_samplers(prog, "u_previous", [prev], 0)
        current.bind_to_image(0, read=True, write=True)
        dispatch(prog, faces.grid.size)
        ctx.memory_barrier()
    return {"bounce": bounces, "flux": [float(f) for f in flux[-1] + added[-1] * tail], "extrapolated": True,
            "ratio": [float(r) for r in ratio]}
