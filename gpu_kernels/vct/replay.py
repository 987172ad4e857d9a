# SPDX-License-Identifier: GPL-3.0-or-later
"""vct_hits: the per-pixel sub-rays' hits, kept so that a light or world edit replays the per-pixel trace instead
of tracing it again (vct/hits.glsl says why that gives the same image bit for bit).

The first vct_trace over a G-buffer records, for every traced texel, each point where a sub-ray met a surface:
where it read which volume at which level, and how much of the sub-ray that surface absorbed. Those depend on the
geometry, the camera and the trace settings only (the pass's key), so while they hold, vct_trace reads each hit's
radiance from the new volumes and sums — one texture read per hit instead of the march that found it. The pool is
capped (BUDGET_BYTES): a texel whose hits no longer fit is marked, and a replay traces it again.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gl.bind import set_uniform

HIT_CHUNK = 16  # slots per chunk (vct/hits.glsl HIT_CHUNK)
# Chunks a texel may take on average (the pool's size): 256 hits. Measured, hits per traced texel at the defaults
# (16 cones × 5 sub-rays): Cornell box mean 122, max 214; window_room 116 / 185; outdoor 70 / 247; furnished
# 156 / 406 — the pool is shared, so a texel with many hits takes what others leave.
CHUNKS_PER_TEXEL = 16
# The pool's cap (as the LPV's transfer_mb): 1.0 × 10⁵ traced texels at CHUNKS_PER_TEXEL, about twice as many once
# sized from a prior record (a 1280 × 640 image at indirect_scale 2).
BUDGET_BYTES = 512 * 2 ** 20
SLOT_BYTES = 16 + 4  # a point (q, α) and a tag
CHUNK_BYTES = HIT_CHUNK * SLOT_BYTES + 4  # and the index of the next chunk
HEADER_BYTES = 16


@dataclass
class TraceHits:
    """The hit pool of one traced image of `size` texels (vct/hits.glsl's buffers 4–7). `recorded`: a trace has
    filled it; `needed`: the chunks that trace asked for (more than `capacity`: some texels are traced again)."""
    headers: object
    points: object
    tags: object
    next: object
    size: tuple
    capacity: int
    recorded: bool = False
    needed: int = 0

    @property
    def nbytes(self) -> int:
        return sum(b.size for b in (self.headers, self.points, self.tags, self.next))

    def release(self) -> None:
        for b in (self.headers, self.points, self.tags, self.next):
            b.release()


def allocate(ctx, size: tuple, prior: TraceHits | None = None, budget: int | None = None) -> TraceHits:
    """An empty pool for a traced image of `size` = (w, h) texels: CHUNKS_PER_TEXEL chunks a texel, or, after
    a `prior` record that kept every texel (the last view of the scene), a quarter more than it needed a texel."""
    texels = int(size[0]) * int(size[1])
    budget = BUDGET_BYTES if budget is None else budget
    per_texel = float(CHUNKS_PER_TEXEL)
    if prior is not None and prior.recorded and prior.needed <= prior.capacity:
        per_texel = min(per_texel, 1.25 * prior.needed / max(prior.size[0] * prior.size[1], 1) + 1.0)
    # A storage block's size is capped too (128 MiB on llvmpipe): the points' buffer must fit in one.
    block = int(ctx.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 2 ** 27))
    capacity = max(1, min(int(per_texel * texels), (budget - HEADER_BYTES * texels) // CHUNK_BYTES,
                          block // (16 * HIT_CHUNK)))
    slots = capacity * HIT_CHUNK
    return TraceHits(ctx.buffer(reserve=HEADER_BYTES * texels), ctx.buffer(reserve=16 * slots),
                     ctx.buffer(reserve=4 * slots), ctx.buffer(reserve=4 * capacity), tuple(size), capacity)


def bind(prog, hits: TraceHits, counter) -> None:
    """The pool on storage buffers 4–7 and the chunk counter on 3 (vct/hits.glsl)."""
    counter.bind_to_storage_buffer(3)
    for binding, b in enumerate((hits.headers, hits.points, hits.tags, hits.next), start=4):
        b.bind_to_storage_buffer(binding)
    set_uniform(prog, "u_chunk_capacity", hits.capacity)


def new_counter(ctx):
    return ctx.buffer(np.zeros(4, np.uint32).tobytes())


def read_count(counter) -> int:
    return int(np.frombuffer(counter.read(), np.uint32)[0])


def stats(hits: TraceHits | None) -> dict:
    """render --json info: the pool's size and whether every texel's hits fit."""
    if hits is None:
        return {}
    return {"trace_hits": {"mib": round(hits.nbytes / 2 ** 20, 1), "chunks": min(hits.needed, hits.capacity),
                           "all_kept": hits.needed <= hits.capacity}}
