# SPDX-License-Identifier: GPL-3.0-or-later
"""The sky light's visible shares per G-buffer pixel (direct/light.glsl MODE_SKY, direct/sky.glsl): one shadow test
per direction of the sky, hundreds of them, each cell an opening's edge crosses tested over its cone, and the
diffuse share then averaged over each pixel's penumbra (direct/sky_filter.glsl). The pipeline keeps them across
light, material and world edits (they depend on the G-buffer and the sky's maps only); after an object's move only
the pixels whose tests can read a texel it redrew are made anew (SkyUpdate)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..common import lights as lb
from ..gl.bind import bind_light_records, bind_samplers, dispatch, read_texture, set_uniform, set_uniforms, ssbo
from .gbuffer import GBuffer
from .lighting import bind_inputs
from .shadows import ShadowAtlas

TILE = 8  # pixels per side of a work group of direct/light.glsl: the blocks an update lists directions for
NEAREST = 6  # per sky direction, its nearest others (and those that have it among theirs: neighbours)


@dataclass
class SkyShares:
    """`texture`: RGBA32F, per pixel the shares of the sky's cosine weight (x) and of the glossy lobe's (y) that its
    directions' tests find visible, and the penumbra's half-width (z, m), the diffuse share filtered; `raw`: the
    same unfiltered, which an object's move keeps where it cannot change them; `made_from`: the depth atlas
    (serial, generation), the scene's triangles and the G-buffer's key they were made with."""
    texture: object
    raw: object
    made_from: tuple = None

    def release(self):
        for t in (self.texture, self.raw):
            t.release()


@dataclass
class SkyUpdate:
    """What an object's move leaves of an earlier SkyShares of the same G-buffer (but where the move covers it) and
    sky, made from the depth atlas one update ago: `pixels` (x0, y0, x1, y1) the G-buffer rectangle the moved
    triangles can cover (made anew there), `table` (K, 4) int32 per sky direction the box of the texels its redraw
    changed (direct/sky.glsl SkyRedrawn)."""
    prior: SkyShares
    pixels: tuple
    table: np.ndarray


def sky_light(shadows: ShadowAtlas) -> int | None:
    """The index of the sky light (the world as a light) among the light records, None where there is none."""
    kinds = shadows.buffers.lights["color_type"][:, 3].astype(int)
    found = np.nonzero(kinds == lb.LIGHT_SKY)[0]
    return int(found[0]) if len(found) else None


def render_sky_visibility(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas, material_lut=None,
                          update: SkyUpdate | None = None) -> SkyShares | None:
    """The sky light's SkyShares, or None where the scene has no sky light. With `update`, a pixel outside its
    moved rectangle whose tests read no texel the move redrew keeps its earlier shares: the same shares as a cold
    render (tests/gpu/test_sky_update.py)."""
    sky = sky_light(shadows)
    if sky is None:
        return None
    w, h = gbuffer.size
    raw = ctx.texture((w, h), 4, dtype="f4")
    first, count = (int(v) for v in shadows.buffers.lights[sky]["params"][1:3])
    table = neighbours(np.array([v.emit_normal for v in shadows.buffers.views[first:first + count]]).tobytes())
    prog = programs.compute("direct/light.glsl", {"MODE_SKY": None, "SKY_NEIGHBOURS": table.shape[1],
                                                  **shadows.defines})
    raw.bind_to_image(2, read=False, write=True)
    unit = bind_inputs(prog, gbuffer, shadows, material_lut)
    set_uniforms(prog, {"u_sky_update": update is not None,
                        "u_moved_pixels": tuple(update.pixels) if update else (0, 0, 0, 0)})
    buffers = []
    if update is not None:
        bind_samplers(prog, "u_sky_prior", [update.prior.raw], unit)
        buffers.append(ssbo(ctx, update.table))
        buffers[0].bind_to_storage_buffer(11)  # read by tile_directions too
        buffers.append(tile_directions(ctx, programs, gbuffer, shadows, update))
        bind_light_records(shadows)
        buffers[1].bind_to_storage_buffer(13)
        set_uniforms(prog, {"u_tiles_x": -(-w // TILE), "u_sky_words": -(-len(update.table) // 32)})
    buffers.append(ssbo(ctx, table))
    buffers[-1].bind_to_storage_buffer(14)  # after tile_directions, whose output binds there
    dispatch(prog, (w, h), local=TILE)
    for buffer in buffers:
        buffer.release()
    return SkyShares(filter_sky_shares(ctx, programs, gbuffer, raw), raw)


@lru_cache(maxsize=4)
def neighbours(directions: bytes) -> np.ndarray:
    """(K, N) int32: per sky direction (the float64 unit vectors' bytes, K × 3), its NEAREST nearest others and
    every direction that has it among its own nearest, padded with its own index: the relation made mutual, so that
    the edge cells direct/sky.glsl marks from the seen side and from the blocked side are the same."""
    dirs = np.frombuffer(directions, np.float64).reshape(-1, 3)
    k = min(NEAREST, len(dirs) - 1)
    if k < 1:
        return np.zeros((len(dirs), 1), np.int32)
    near = np.argsort(-(dirs @ dirs.T), axis=1)[:, 1:k + 1]
    sets = [set(row) for row in near.tolist()]
    for i, row in enumerate(near.tolist()):
        for j in row:
            sets[j].add(i)
    width = max(len(s) for s in sets)
    return np.array([sorted(s) + [i] * (width - len(s)) for i, s in enumerate(sets)], np.int32)


def tile_boxes(gbuffer: GBuffer, moved: tuple) -> np.ndarray:
    """(tiles, 2, 4) float32: per TILE × TILE block of pixels (row by row), the box (lo, hi) of the G-buffer points
    an update may keep — those outside the `moved` rectangle (x0, y0, x1, y1); an empty box
    (lo > hi) where there are none."""
    w, h = gbuffer.size
    position = read_texture(gbuffer.textures["position"])[::-1]  # (h, w, 4), row 0 the texels' y = 0
    x, y = np.meshgrid(np.arange(w), np.arange(h))
    x0, y0, x1, y1 = moved
    used = (position[..., 3] >= 0.5) & ~((x >= x0) & (x < x1) & (y >= y0) & (y < y1))
    tw, th = -(-w // TILE), -(-h // TILE)
    pad = np.zeros((th * TILE, tw * TILE, 3), np.float32)
    lo, hi = np.full_like(pad, np.inf), np.full_like(pad, -np.inf)
    lo[:h, :w] = np.where(used[..., None], position[..., :3], np.inf)
    hi[:h, :w] = np.where(used[..., None], position[..., :3], -np.inf)
    out = np.zeros((th, tw, 2, 4), np.float32)
    out[:, :, 0, :3] = lo.reshape(th, TILE, tw, TILE, 3).min(axis=(1, 3))
    out[:, :, 1, :3] = hi.reshape(th, TILE, tw, TILE, 3).max(axis=(1, 3))
    return np.nan_to_num(out.reshape(-1, 2, 4), posinf=3.4e38, neginf=-3.4e38)


def tile_directions(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas, update: SkyUpdate):
    """Per TILE × TILE block, one bit per sky direction whose changed box a test at one of the block's points
    that may be kept can read (direct/sky_tiles.glsl): a buffer the update reads (direct/sky.glsl SkyTiles)."""
    w, h = gbuffer.size
    boxes = ssbo(ctx, tile_boxes(gbuffer, update.pixels))
    tiles, words = (-(-w // TILE)) * (-(-h // TILE)), -(-len(update.table) // 32)
    out = ctx.buffer(reserve=4 * tiles * words)
    prog = programs.compute("direct/sky_tiles.glsl")
    bind_light_records(shadows)
    sky = sky_light(shadows)
    set_uniforms(prog, {"u_first_view": int(shadows.buffers.lights[sky]["params"][1]), "u_tiles": tiles,
                        "u_directions": len(update.table), "u_words": words,
                        "u_atlas_texel": (1.0 / shadows.size[0], 1.0 / shadows.size[1])})
    boxes.bind_to_storage_buffer(13)
    out.bind_to_storage_buffer(14)
    dispatch(prog, (tiles * words,), local=64)
    ctx.memory_barrier()
    boxes.release()
    return out


def update_table(shadows: ShadowAtlas) -> np.ndarray | None:
    """SkyUpdate.table for the sky light's directions from the depth atlas's last update (shadows.maps: redrawn,
    and which of the texels each redraw overwrote it changed); None where it cannot serve: a sky view drawn whole,
    or its overwritten texels not kept (what changed in it is not known)."""
    maps = shadows.maps
    if maps is None or maps.redrawn is None or maps.overwritten is None:
        return None
    sky = sky_light(shadows)
    if sky is None:
        return None
    first, count = (int(v) for v in shadows.buffers.lights[sky]["params"][1:3])
    table = np.zeros((count, 4), np.int32)
    kept, changed = maps.overwritten.rects, maps.overwritten.changed
    for view, rect in maps.redrawn:
        if not first <= view < first + count:
            continue
        if rect is None or view not in kept:
            return None
        table[view - first] = changed[view] or (0, 0, 0, 0)
    return table


def filter_sky_shares(ctx, programs, gbuffer: GBuffer, shares):
    """The sky's diffuse share averaged over each pixel's penumbra on its own surface, one image axis at a time
    (direct/sky_filter.glsl); keeps `shares`."""
    w, h = gbuffer.size
    prog = programs.compute("direct/sky_filter.glsl")
    unit = bind_samplers(prog, "u_position", [gbuffer.textures["position"]], 0)
    unit = bind_samplers(prog, "u_geo_normal", [gbuffer.textures["geo_normal"]], unit)
    set_uniform(prog, "u_size", (w, h))
    source = shares
    for axis in ((1, 0), (0, 1)):
        out = ctx.texture((w, h), 4, dtype="f4")
        bind_samplers(prog, "u_shares", [source], unit)
        out.bind_to_image(0, read=False, write=True)
        set_uniform(prog, "u_axis", axis)
        dispatch(prog, (w, h), local=8)
        if source is not shares:
            source.release()
        source = out
    return source
