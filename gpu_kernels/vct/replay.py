# SPDX-License-Identifier: GPL-3.0-or-later
"""Pools of recorded cone samples, replayed instead of marching the cones again (vct/hits.glsl says why that gives
the same result bit for bit): the per-pixel sub-rays' hits (vct_hits) and the bounce gathers' steps
(volumes.VoxelGeometry.gather_pool).

The first vct_trace over a G-buffer records, for every traced texel, each point where a sub-ray met a surface:
where it read which volume at which level, and how much of the sub-ray that surface absorbed. Those depend on the
geometry, the camera and the trace settings only (the pass's key), so while they hold, vct_trace reads each hit's
radiance from the new volumes and sums — one texture read per hit instead of the march that found it. Likewise the
first bounce gather records, per face, the steps of its cones that absorbed light (where, the axes' weights, the
opacity and the cone's transmittance there), which the later bounces and every bounce after a light edit replay. A
pool is capped (BUDGET_BYTES, and a storage block's size): an item whose records no longer fit is marked, and a
replay marches it again.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ..gl.bind import set_uniform

HIT_CHUNK = 16  # slots per chunk (vct/hits.glsl HIT_CHUNK)
# Chunks a texel may take on average (the pool's size): 256 hits. Measured, hits per traced texel at the defaults
# (16 cones × 5 sub-rays): Cornell box mean 122, max 214; window_room 116 / 185; outdoor 70 / 247; furnished
# 156 / 406 — the pool is shared, so a texel with many hits takes what others leave.
CHUNKS_PER_TEXEL = 16
# Chunks a bounce gather's face may take on average: 48 steps. Measured, the Cornell box's 60 796 faces: 28.7 steps
# that absorbed light a face (of 94 taken), 6 cones.
CHUNKS_PER_FACE = 3
# A pool's cap (as the LPV's transfer_mb): 1.0 × 10⁵ traced texels at CHUNKS_PER_TEXEL, about twice as many once
# sized from a prior record (a 1280 × 640 image at indirect_scale 2).
BUDGET_BYTES = 512 * 2 ** 20
HEADER_BYTES = 16
# Bytes a slot takes, per storage buffer binding (vct/hits.glsl): the trace's hit (q, α) and tag, a gather's step.
TRACE_SLOTS = {5: 16, 6: 4}
GATHER_SLOTS = {6: 48}


@dataclass
class HitPool:
    """Records of `items` items (traced texels, or faces a bounce gathers at) in chunks (vct/hits.glsl): headers
    on storage buffer 4, the chunks' links on 7, the records on `payload` (binding → buffer). `recorded`: a pass has
    filled it; `needed`: the chunks it asked for (more than `capacity`: some items were not kept and run again);
    `key`: what the records were made under, where the pool's holder does not key it."""
    headers: object
    payload: dict
    next: object
    size: tuple
    capacity: int
    recorded: bool = False
    needed: int = 0
    key: object = None

    @property
    def items(self) -> int:
        return int(np.prod(self.size))

    @property
    def nbytes(self) -> int:
        return sum(b.size for b in (self.headers, self.next, *self.payload.values()))

    def release(self) -> None:
        for b in (self.headers, self.next, *self.payload.values()):
            b.release()


def chunk_bytes(slots: dict) -> int:
    """A chunk's bytes: its slots' records and the link to the next chunk."""
    return HIT_CHUNK * sum(slots.values()) + 4


def allocate(ctx, size: tuple, prior: HitPool | None = None, budget: int | None = None,
             slots: dict | None = None, per_item: float = CHUNKS_PER_TEXEL) -> HitPool:
    """An empty pool for `size` = (w, h) traced texels (or (faces,) with slots=GATHER_SLOTS): `per_item` chunks an
    item, or, after a `prior` record that kept every item (the last view of the scene), a quarter more than it
    needed an item."""
    slots = TRACE_SLOTS if slots is None else slots
    items = int(np.prod(size))
    budget = BUDGET_BYTES if budget is None else budget
    if prior is not None and prior.recorded and prior.needed <= prior.capacity:
        per_item = min(per_item, 1.25 * prior.needed / max(prior.items, 1) + 1.0)
    # A storage block's size is capped too (128 MiB on llvmpipe): each record buffer must fit in one.
    block = int(ctx.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 2 ** 27))
    capacity = max(1, min(int(per_item * items), (budget - HEADER_BYTES * items) // chunk_bytes(slots),
                          block // (max(slots.values()) * HIT_CHUNK)))
    payload = {binding: ctx.buffer(reserve=width * HIT_CHUNK * capacity) for binding, width in slots.items()}
    headers = ctx.buffer(reserve=HEADER_BYTES * items)
    headers.clear()  # state 0, "not recorded", for an item the record passes by (a face then without albedo)
    return HitPool(headers, payload, ctx.buffer(reserve=4 * capacity), tuple(size), capacity)


# Faces with coverage a bounce gathers at, per cell² of surface area: the stress tests' closed box room 2.2 at 16³,
# 32³ and 64³ (a wall's voxels have both faces along its normal, and an edge's more).
FACES_PER_CELL_AREA = 2.5


def pool_bytes(area: float, cell: float, traced: tuple) -> int:
    """About how many bytes the two pools take for a scene of `area` m² on a grid of `cell` m and a trace of `traced`
    = (w, h) texels (settings.method_bytes): each at its first size, within BUDGET_BYTES."""
    return hits_bytes(traced) + steps_bytes(area, cell)


def hits_bytes(traced: tuple) -> int:
    """The per-pixel trace's pool for `traced` = (w, h) texels at its first size, within BUDGET_BYTES."""
    texels = int(traced[0]) * int(traced[1])
    return int(min(HEADER_BYTES * texels + CHUNKS_PER_TEXEL * texels * chunk_bytes(TRACE_SLOTS), BUDGET_BYTES))


def steps_bytes(area: float, cell: float) -> int:
    """The bounce gathers' pool for `area` m² of surface on a grid of `cell` m, within BUDGET_BYTES."""
    faces = FACES_PER_CELL_AREA * area / cell ** 2
    return int(min(faces * (HEADER_BYTES + CHUNKS_PER_FACE * chunk_bytes(GATHER_SLOTS)), BUDGET_BYTES))


@contextmanager
def pooled(ctx, prog, pool: HitPool | None):
    """Around the dispatches of `prog` that record into or replay from `pool` (none: nothing): the pool on storage
    buffers 4, 7 and its payload's, a chunk counter on 3 (vct/hits.glsl); a pool not yet recorded is marked
    recorded afterwards, with the chunks the dispatches asked for."""
    if pool is None:
        yield
        return
    counter = ctx.buffer(np.zeros(4, np.uint32).tobytes())
    try:
        counter.bind_to_storage_buffer(3)
        pool.headers.bind_to_storage_buffer(4)
        pool.next.bind_to_storage_buffer(7)
        for binding, b in pool.payload.items():
            b.bind_to_storage_buffer(binding)
        set_uniform(prog, "u_chunk_capacity", pool.capacity)
        yield
        if not pool.recorded:
            pool.recorded, pool.needed = True, int(np.frombuffer(counter.read(), np.uint32)[0])
    finally:
        counter.release()


def stats(pool: HitPool | None, name: str = "trace_hits") -> dict:
    """render --json info: the pool's size and whether every item's records fit."""
    if pool is None or not pool.recorded:
        return {}
    return {name: {"mib": round(pool.nbytes / 2 ** 20, 1), "chunks": min(pool.needed, pool.capacity),
                   "all_kept": pool.needed <= pool.capacity}}
