# SPDX-License-Identifier: GPL-3.0-or-later
"""Temporal accumulation of the VCT diffuse gather, for interactive updates (Freed 2018, §4.7.2, blends voxel radiance
over frames against flicker; here the pixels' gathers are averaged instead, with a hard reset rather than a blend).

A few cones integrate the hemisphere coarsely: the cone set sees a bright patch or misses it depending on how it is
turned about the normal. Each render of an unchanged view k = 0, 1, … turns the set by another angle (`jitter_deg`)
and the history keeps the mean of frames 0..k (vct/accumulate.glsl), so the picture converges to the average over
turns. Frame 0 is unrotated, so the first frame after a reset equals a render without accumulation. The history is
keyed by every input of the trace (G-buffer: geometry, materials, camera; bounced volumes: lights, VCT
settings; the trace settings): a change restarts it at frame 0, so nothing of the old scene survives (no ghosting).
vct/passes._per_pixel advances one frame per render until VctSettings.temporal_frames are in, then skips.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..gl.bind import bind_samplers, dispatch, set_uniform
from .cones import ring_sizes
from .settings import VctSettings


def radical_inverse(k: int) -> float:
    """Van der Corput (base 2): 0, ½, ¼, ¾, ⅛, … — every prefix of the sequence spreads evenly over [0, 1)."""
    x, f = 0.0, 0.5
    while k:
        x += f * (k & 1)
        k >>= 1
        f *= 0.5
    return x


def jitter_deg(s: VctSettings, frame: int) -> float:
    """The cone set's turn about the normal (degrees) for accumulation frame `frame`: s.cone_rotation plus a
    van der Corput fraction of the first ring's spacing 360°/m (a turn by it gives the same set: the second ring,
    if any, has 2m sectors)."""
    return s.cone_rotation + 360.0 / ring_sizes(s.diffuse_cones)[1] * radical_inverse(frame)


@dataclass
class History:
    """The running mean (RGBA32F: Diffuse Indirect, AO) of `frames` jittered frames of the inputs keyed `base`."""
    texture: object
    base: tuple
    frames: int = 0

    def release(self):
        self.texture.release()


def frame_index(history: History | None, base: tuple, frames: int) -> int:
    """The frame the next render traces: how many are in (0 after any change of `base`), held at frames − 1 once
    complete (so the pass keys repeat and the cache skips the trace)."""
    done = history.frames if history is not None and history.base == base else 0
    return min(done, max(frames, 1) - 1)


def accumulate(ctx, programs, history: History | None, current, base: tuple, frame: int) -> History:
    """Fold `current` (RGBA32F at full resolution) into the history as frame `frame` (0 restarts it). Reuses the
    history's texture in place when the size matches (the pass cache then keeps it)."""
    size = current.size
    if history is None or history.texture.size != size:
        history = History(ctx.texture(size, 4, dtype="f4"), base)
    history.base, history.frames = base, frame + 1
    prog = programs.compute("vct/accumulate.glsl")
    bind_samplers(prog, "u_current", [current], 0)
    set_uniform(prog, "u_image_size", tuple(size))
    set_uniform(prog, "u_frame", int(frame))
    history.texture.bind_to_image(0, read=True, write=True)
    dispatch(prog, (size[0], size[1]), local=8)
    ctx.memory_barrier()
    return history
