# SPDX-License-Identifier: GPL-3.0-or-later
"""compose: the GPU results read back and combined into Cycles-named passes (numpy), every method alike."""
from __future__ import annotations

import numpy as np

from .gl.bind import read_texture

PASS_NAMES = ("Combined", "Diffuse Direct", "Diffuse Indirect", "Diffuse Color", "Glossy Direct", "Glossy Indirect",
              "Glossy Color",
              "Emission", "AO", "Normal", "Position", "Depth")
BACKGROUND_DEPTH = 1e10  # Cycles writes 1e10 to the Depth pass where no geometry was hit


def compose_passes(gbuffer, direct: dict, world_color, indirect: np.ndarray | None = None,
                   glossy: np.ndarray | None = None, ao: np.ndarray | None = None) -> dict:
    """Read the GPU results back and build the Cycles-named passes; Combined = (direct+indirect)·colour +
    (Glossy Direct + Glossy Indirect)·Glossy Color + emission. `direct`: direct/lighting.render_direct_light's.
    `glossy`: (H, W, 4), rgb Glossy Indirect where a glossy ray was traced (a = 1). Where none was (the LPV,
    lobes above the VCT's roughness cutoff) the diffuse indirect light stands for the glossy one: the two are equal
    when the indirect light arrives alike from every direction, which a rough lobe averages towards. `indirect`, `glossy`: (H, W, 3) Diffuse / Glossy Indirect; `ao`: (H, W)
    voxel AO. Methods without them get zeros (AO: 1 on geometry), so every method writes the same passes."""
    position = read_texture(gbuffer.textures["position"])
    hit = position[..., 3:4] > 0.5
    normal = read_texture(gbuffer.textures["normal"])
    albedo = read_texture(gbuffer.textures["albedo"], 3) * hit
    glossy_color = read_texture(gbuffer.textures["glossy"], 3) * hit
    emission = read_texture(gbuffer.textures["emission"], 3) * hit
    # Cycles divides its light passes by Diffuse Color per channel and writes 0 where that colour is 0
    # (safe_divide_even_color), so a surface with no diffuse part shows no diffuse light; glossy likewise.
    has_diffuse = albedo > 0
    diffuse_direct = direct["diffuse"] * has_diffuse
    glossy_direct = direct["glossy"] * (glossy_color > 0)
    diffuse_indirect = np.zeros_like(diffuse_direct) if indirect is None else indirect * has_diffuse
    traced = np.zeros(albedo.shape[:2] + (1,), bool) if glossy is None else glossy[..., 3:4] > 0.5
    stand_in = np.zeros_like(diffuse_direct) if indirect is None else indirect
    glossy_indirect = np.where(traced, 0.0 if glossy is None else glossy[..., :3], stand_in) * (glossy_color > 0)
    ao_pass = np.repeat((hit[..., 0] if ao is None else ao * hit[..., 0])[..., None], 3, axis=2)
    combined = np.empty(albedo.shape[:2] + (4,), np.float32)
    combined[..., :3] = np.where(hit, (diffuse_direct + diffuse_indirect) * albedo
                                 + (glossy_direct + glossy_indirect) * glossy_color
                                 + emission, np.asarray(world_color, np.float32)[:3])
    combined[..., 3] = 1.0  # the world is visible to the camera (film not transparent), as in Cycles' default
    depth = np.where(hit, normal[..., 3:4], BACKGROUND_DEPTH).astype(np.float32)
    return {
        "Combined": combined,
        "Diffuse Direct": diffuse_direct.astype(np.float32),
        "Diffuse Indirect": diffuse_indirect.astype(np.float32),
        "Diffuse Color": albedo.astype(np.float32),
        "Glossy Direct": glossy_direct.astype(np.float32),
        "Glossy Indirect": glossy_indirect.astype(np.float32),
        "Glossy Color": glossy_color.astype(np.float32),
        "Emission": emission.astype(np.float32),
        "AO": ao_pass.astype(np.float32),
        "Normal": (normal[..., :3] * hit).astype(np.float32),
        "Position": (position[..., :3] * hit).astype(np.float32),
        "Depth": depth,
    }
