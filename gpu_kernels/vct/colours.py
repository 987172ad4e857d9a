# SPDX-License-Identifier: GPL-3.0-or-later
"""The VCT's transport per unit of the lights' colours: every pass from vct_inject on runs on the lights' colours
divided, per channel, by the largest of them (colour_scale), and its results are multiplied back (scale_output).

Why: the transport is linear in the light injected per channel — the injection, the mips, each bounce's gather, the
tail's ratio (per channel) and the per-pixel cones; the series' stop (epsilon) is relative — so an edit that scales
every light alike leaves the divided colours, and with them every VCT pass, as they were: the power or colour of a
scene's only lamp, the strength or colour of a sky-lit scene's world. Such an edit then costs the direct light and
two small textures' rescale, not the bounces (seconds on llvmpipe). Any other light edit changes the divided colours
and re-runs the transport as before. A cold render goes through the same division, so it gives what an edit does.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..gl.bind import ssbo


def colour_scale(shadows) -> np.ndarray:
    """(3,) float32: per channel, the largest colour (colour × power or strength) of the scene's lights; 1 where no
    light has any."""
    return largest_colour(shadows.buffers.lights["color_type"][:, :3])


def largest_colour(colours: np.ndarray) -> np.ndarray:
    """(3,) float32: per channel, the largest of `colours` (N, 3); 1 where none is above 0."""
    largest = np.asarray(colours).max(axis=0, initial=0.0).astype(np.float32)
    return np.where(largest > 0, largest, np.float32(1.0))


def unit_records(shadows, scale: np.ndarray, lights: np.ndarray) -> np.ndarray:
    """The light records at the indices `lights` with their colours divided by `scale` (what a part of vct_inject
    lights the voxels with, vct/parts.py)."""
    records = shadows.buffers.lights[lights].copy()
    records["color_type"][:, :3] /= scale
    return records


def with_records(ctx, shadows, records: np.ndarray, run):
    """run(shadows') with shadows' lights `records` (all of them, or some: vct/parts.py), uploaded for the call."""
    buffer = ssbo(ctx, records)
    shadows.raw_depth()  # made on the original, so the copy shares it and nothing is left unreleased
    try:
        return run(replace(shadows, light_ssbo=buffer, light_count=len(records)))
    finally:
        buffer.release()


def scale_output(ctx, textures: list, scale: np.ndarray) -> tuple:
    """New RGBA32F textures: each of `textures` (None kept) with rgb × `scale`, alpha (the voxel AO, the glossy
    cone's flag) as it is."""
    out = []
    for texture in textures:
        if texture is None:
            out.append(None)
            continue
        w, h = texture.size
        data = np.frombuffer(texture.read(), np.float32).reshape(h, w, 4).copy()
        data[..., :3] *= scale
        scaled = ctx.texture((w, h), 4, data.tobytes(), dtype="f4")
        scaled.filter = texture.filter
        out.append(scaled)
    return tuple(out)


def scale_info(info: dict, scale: np.ndarray) -> dict:
    """The bounce statistics' flux (per unit colour in the passes) in watts."""
    bounces = [dict(b, flux=[float(f) * float(s) for f, s in zip(b["flux"], scale)]) for b in info.get("bounces", [])]
    return {**info, "bounces": bounces}
