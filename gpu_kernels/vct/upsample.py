# SPDX-License-Identifier: GPL-3.0-or-later
"""Reduced-resolution VCT gather brought back to full resolution (inferred lighting, Kircher and Lawrance 2009:
lighting at a reduced resolution plus discontinuity-aware upsampling).

vct/trace.glsl gathers at every s-th G-buffer pixel (VctSettings.indirect_scale = s: s² fewer cone sets);
vct/upsample.glsl blends the 2×2 nearest gathers with bilinear × tangent-plane-distance × normal weights, and pixels
whose surface none of them lies on are traced again at full resolution (vct/trace.glsl MODE_MARKED), so light never
crosses a depth or normal discontinuity. The trade (time against Diffuse Indirect error vs Cycles) is measured in
benchmarks/vct_bench.py.
"""
from __future__ import annotations

from ..gl.bind import bind_samplers, dispatch_counted, set_uniforms
from .trace import marked_list, trace_marked

SIGMA_VOXELS = 0.5  # plane-distance scale in voxels (vct/upsample.glsl says why)


def upsample(ctx, programs, gbuffer, low: dict, faces, volumes, s, rotation_deg=None) -> dict:
    """{'indirect': full-resolution RGBA32F texture (rgb Diffuse Indirect, a AO), 'fixup': pixels traced again at
    full resolution}. `low` is vct/trace.trace's output at s.indirect_scale."""
    listed = marked_list(ctx, gbuffer.size)
    try:
        out, marked = joint_bilateral(ctx, programs, gbuffer, low["indirect"], int(low["scale"]),
                                      SIGMA_VOXELS * volumes.grid.cell, listed)
        trace_marked(ctx, programs, gbuffer, faces, volumes, s, out, 1, listed, marked, rotation_deg)
    finally:
        listed.release()
    return {"indirect": out, "fixup": marked}


def joint_bilateral(ctx, programs, gbuffer, low, scale: int, sigma: float, listed=None):
    """vct/upsample.glsl alone: (full-resolution RGBA32F texture, pixels marked a = −1 for a full-resolution trace,
    listed in `listed` where given: trace.marked_list). `low` holds the values at G-buffer pixels i·scale + scale/2;
    `sigma` is the plane-distance scale (m)."""
    w, h = gbuffer.size
    own = listed is None  # the shader lists the marked pixels all the same
    listed = marked_list(ctx, gbuffer.size) if own else listed
    listed.bind_to_storage_buffer(5)
    out = ctx.texture((w, h), 4, dtype="f4")
    prog = programs.compute("vct/upsample.glsl")
    unit = bind_samplers(prog, "u_low", [low], 0)
    for name in ("position", "normal"):
        unit = bind_samplers(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    set_uniforms(prog, {"u_image_size": (w, h), "u_low_size": tuple(low.size), "u_scale": int(scale),
                        "u_sigma": float(sigma)})
    out.bind_to_image(0, read=False, write=True)
    try:
        return out, dispatch_counted(ctx, prog, (w, h))
    finally:
        if own:
            listed.release()
