# SPDX-License-Identifier: GPL-3.0-or-later
"""VCT specular cone (Freed 2018, §4.5.2: five diffuse cones and one specular cone): one glossy cone per G-buffer pixel
along the reflected view direction → the Glossy Indirect pass (vct/specular.glsl).

Aperture: Blender's GGX has α = roughness². Half of the GGX microfacet normals lie within atan(α) of the normal
(GGX sampling, Walter et al. 2007: tan²θ_h = α²ξ/(1 − ξ), median at ξ = ½), and the reflected ray turns by twice
the normal's tilt, so the cone's half-angle is 2·atan(α) — the median of the reflected lobe — capped at 45°.
`aperture_deg` gives it.
Pixels rougher than VctSettings.roughness_cutoff, or with no glossy closure (Glossy Color 0), run no cone and get 0,
so a scene without glossy materials pays one texture fetch per pixel (measured in benchmarks/vct_bench.py).
Glossy Color comes from the G-buffer (direct/gbuffer.glsl: Cycles' glossy albedo); Combined adds Glossy Indirect ×
Glossy Color (compose.compose_passes). Specular light from the lights themselves (Cycles' Glossy Direct) is not
computed.
"""
from __future__ import annotations

import math

import numpy as np

from ..gl.bind import bind_samplers, dispatch_counted, set_uniforms
from .settings import VctSettings
from .trace import bind_cones
from .volumes import ConeVolumes, Faces, bind_volumes

MAX_HALF_ANGLE_DEG = 45.0  # vct/specular.glsl


def aperture_deg(roughness: float) -> float:
    """The specular cone's half-angle (degrees) for Principled roughness r: 2·atan(r²), capped at 45°."""
    return min(math.degrees(2.0 * math.atan(float(roughness) ** 2)), MAX_HALF_ANGLE_DEG)


def specular(ctx, programs, gbuffer, faces: Faces, volumes: ConeVolumes, s: VctSettings) -> dict:
    """{'glossy': RGBA32F texture at full resolution (rgb = Glossy Indirect, a = 1 where a cone ran),
    'traced': pixels that ran a cone}. Nothing is dispatched when s.specular_cone is off (texture of zeros)."""
    w, h = gbuffer.size
    out = ctx.texture((w, h), 4, np.zeros((h, w, 4), np.float32).tobytes() if not s.specular_cone else None,
                      dtype="f4")
    if not s.specular_cone:
        return {"glossy": out, "traced": 0}
    prog = programs.compute("vct/specular.glsl", {"MODE_ANISO": None} if volumes.anisotropic else None)
    unit = bind_volumes(prog, volumes, 0)
    unit = bind_samplers(prog, "u_centroid", faces.centroids, unit)
    for name in ("position", "normal", "geo_normal", "glossy"):
        unit = bind_samplers(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    bind_cones(prog, volumes.grid, volumes.levels, s)
    set_uniforms(prog, {"u_image_size": (w, h), "u_camera_position": gbuffer.eye, "u_camera_forward": gbuffer.forward,
                        "u_camera_ortho": bool(gbuffer.ortho), "u_roughness_cutoff": float(s.roughness_cutoff)})
    out.bind_to_image(0, read=False, write=True)
    return {"glossy": out, "traced": dispatch_counted(ctx, prog, (w, h))}


def skipped_work(result: dict, s: VctSettings) -> list:
    """The specular cones left out, in words (render --json "skipped_work", the panel): all of them when the
    setting is off or no pixel has a glossy closure smoother than the cutoff (Glossy Indirect is then 0)."""
    if not s.specular_cone:
        return ["specular cones: off (specular_cone)"]
    if result["traced"] == 0:
        return [f"specular cones: no pixel has a glossy closure smoother than roughness {s.roughness_cutoff:g}"]
    return []
