# SPDX-License-Identifier: GPL-3.0-or-later
"""The surface atlas as a G-buffer: one "pixel" per atlas texel, holding the surface point the texel stands for.

The direct light and every GI method's final gather read a G-buffer (direct/gbuffer.GBuffer) and know nothing of
cameras beyond it, so handing them this one computes Diffuse Direct and Diffuse Indirect at every texel with the
very shaders that light the camera's pixels: the viewport's lighting is the render's, evaluated at other points.
The back page holds the same points with both normals flipped (two-sided surfaces, as the camera G-buffer flips
them toward the viewer). No glossy colour: view-dependent light is not stored (the VCT's specular cone skips
texels without a glossy closure).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..direct.gbuffer import GBUFFER_TARGETS, GBuffer
from ..scene import Scene, hash_parts
from .atlas import SurfaceAtlas


POINTS_PER_ROW = 256


@dataclass(frozen=True)
class Samples:
    """Surface points lit instead of the camera's pixels (pipeline.render_surface / render_points): the content
    key of their G-buffer and a function that builds its arrays (gbuffer_arrays' layout)."""
    key: tuple
    arrays: Callable[[], dict]


def atlas_samples(scene: Scene, atlas: SurfaceAtlas) -> Samples:
    return Samples(("atlas", atlas.key), lambda: gbuffer_arrays(surface_points(scene, atlas)))


def point_samples(positions: np.ndarray, normals: np.ndarray) -> Samples:
    """N points, each lit on the side its normal points to: (ceil(N / POINTS_PER_ROW), POINTS_PER_ROW) "pixels",
    point i at row i // POINTS_PER_ROW, column i % POINTS_PER_ROW (rows bottom-up)."""
    pos = np.asarray(positions, np.float32).reshape(-1, 3)
    nrm = np.asarray(normals, np.float32).reshape(-1, 3)
    length = np.linalg.norm(nrm, axis=1, keepdims=True)
    nrm = np.where(length > 1e-12, nrm / np.maximum(length, 1e-12), (0.0, 0.0, 1.0)).astype(np.float32)

    def arrays():
        n, w = len(pos), POINTS_PER_ROW
        h = max(1, -(-n // w))
        out = {name: np.zeros((h * w, 4), np.float32) for name in GBUFFER_TARGETS}
        out["position"][:n] = np.hstack([pos, np.ones((n, 1), np.float32)])
        out["normal"][:n, :3] = out["geo_normal"][:n, :3] = nrm
        out["albedo"][:n] = 1.0
        return {k: v.reshape(h, w, 4) for k, v in out.items()}
    return Samples(("points", hash_parts(pos, nrm)), arrays)


def surface_points(scene: Scene, atlas: SurfaceAtlas) -> dict:
    """Per front-page texel (H, W): "position", "normal", "geo_normal" (xyz, float32), "uv" and "valid"."""
    tri = np.maximum(atlas.triangle, 0)
    valid = atlas.triangle >= 0
    s, t = atlas.bary[..., 0:1], atlas.bary[..., 1:2]
    w = (1 - s - t, s, t)

    def interpolate(corners):
        c = np.asarray(corners, np.float32)[tri]  # (H, W, 3, C)
        return w[0] * c[..., 0, :] + w[1] * c[..., 1, :] + w[2] * c[..., 2, :]

    pos = np.asarray(scene.positions, np.float32)
    geo = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    shading = interpolate(scene.normals)
    geo = geo[tri]
    geo_len = np.linalg.norm(geo, axis=-1, keepdims=True)
    sh_len = np.linalg.norm(shading, axis=-1, keepdims=True)
    shading = np.where(sh_len > 1e-12, shading / np.maximum(sh_len, 1e-12), 0)
    geo = np.where(geo_len > 1e-20, geo / np.maximum(geo_len, 1e-30), shading)  # a sliver: its shading normal
    return {"position": interpolate(pos), "normal": shading, "geo_normal": geo.astype(np.float32),
            "uv": interpolate(scene.uvs), "valid": valid}


def base_colors(scene: Scene, atlas: SurfaceAtlas, points: dict) -> np.ndarray:
    """(H, W, 3) float32: each texel's base colour, its material's constant or its texture at the texel's UV
    (nearest texel, the texture's extension honoured). The viewport multiplies it by the material's diffuse share."""
    tri = np.maximum(atlas.triangle, 0)
    mat = np.asarray(scene.material_index, np.int64)[tri]
    out = np.zeros(atlas.triangle.shape + (3,), np.float32)
    for m, material in enumerate(scene.materials):
        sel = mat == m
        if not sel.any():
            continue
        if 0 <= material.base_color_texture < len(scene.textures):
            out[sel] = sample_texture(scene.textures[material.base_color_texture], points["uv"][sel])
        else:
            out[sel] = np.asarray(material.base_color, np.float32)[:3]
    return out * points["valid"][..., None]


def sample_texture(texture, uv: np.ndarray) -> np.ndarray:
    """Nearest-texel lookup of (N, 2) UVs in a scene Texture (rows bottom-up): RGB (N, 3)."""
    pixels = np.asarray(texture.pixels, np.float32)
    h, w = pixels.shape[:2]
    x, y = np.floor(uv[:, 0] * w).astype(np.int64), np.floor(uv[:, 1] * h).astype(np.int64)
    if texture.extension == "REPEAT":
        x, y = x % w, y % h
    else:
        x, y = np.clip(x, 0, w - 1), np.clip(y, 0, h - 1)
    rgb = pixels[y, x, :3]
    if texture.extension == "CLIP":
        rgb = rgb * ((uv >= 0) & (uv <= 1)).all(axis=1)[:, None]
    return rgb


def gbuffer_arrays(points: dict) -> dict:
    """The G-buffer targets of both pages as (2H, W, 4) float32 arrays, rows bottom-up (front page first)."""
    valid = points["valid"][..., None].astype(np.float32)
    shape = points["valid"].shape + (4,)

    def pages(xyz, w, flip):
        front = np.concatenate([xyz * valid, w * valid], axis=-1)
        back = front.copy()
        if flip:
            back[..., :3] *= -1
        return np.concatenate([front, back], axis=0).astype(np.float32)

    ones, zero = np.ones(shape[:2] + (1,), np.float32), np.zeros(shape[:2] + (1,), np.float32)
    arrays = {"position": pages(points["position"], ones, False),
              "normal": pages(points["normal"], zero, True),
              "geo_normal": pages(points["geo_normal"], zero, True),
              "albedo": pages(np.ones(shape[:2] + (3,), np.float32), ones, False)}
    for name in GBUFFER_TARGETS:
        arrays.setdefault(name, np.zeros((2 * shape[0], shape[1], 4), np.float32))
    return arrays


def upload_gbuffer(ctx, arrays: dict) -> GBuffer:
    """The atlas G-buffer as RGBA32F textures (nearest filtering, as the camera's)."""
    import moderngl

    h, w = arrays["position"].shape[:2]
    textures = {}
    for name in GBUFFER_TARGETS:
        tex = ctx.texture((w, h), 4, np.ascontiguousarray(arrays[name], np.float32).tobytes(), dtype="f4")
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        textures[name] = tex
    depth = ctx.depth_renderbuffer((w, h))
    fbo = ctx.framebuffer(color_attachments=[textures[n] for n in GBUFFER_TARGETS], depth_attachment=depth)
    return GBuffer(textures, depth, fbo, (w, h))
