# SPDX-License-Identifier: GPL-3.0-or-later
"""Diffuse Direct and Glossy Direct: every G-buffer pixel lit by every light, shadowed (direct/light.glsl), by groups
of lights whose images a later frame reuses where their lights did not change."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common import lights as lb
from ..gl.bind import bind_lights, bind_samplers, dispatch, read_texture, set_uniform, set_uniforms, ssbo
from ..scene import hash_parts
from .gbuffer import GBuffer
from .shadows import ShadowAtlas, emitter_records


MAX_UNIT_GROUPS = 16  # lights lit alone per unit of their colour (each keeps two images); the rest share a group


@dataclass
class LightGroup:
    """Lights lit together by one run of direct/light.glsl: `key` says what their light at the pixels is made of
    (with the G-buffer); `unit`: lit per unit of colour, scaled by the light's colour when summed."""
    key: str
    lights: list
    unit: bool


@dataclass
class Relight:
    """What an object's move leaves of an earlier output of render_direct_light (same camera, materials and shadow
    settings, lit from the same depth atlas one update ago): `prior` that output, `pixels` the G-buffer rectangle
    (x0, y0, x1, y1) the moved triangles can cover (direct/gbuffer.box_pixels), `redrawn` the depth atlas's last
    update cut to the texels it changed (shadows.changed_views). A group whose lights are unchanged is lit again only
    at the pixels inside `pixels` or whose shadow tests read a changed texel of its lights' views (direct/light.glsl
    u_masked)."""
    prior: dict
    pixels: tuple
    redrawn: list


def light_groups(shadows: ShadowAtlas) -> list[LightGroup]:
    """The lights in the groups a Diffuse Direct pass sums: each scene light and the sky alone, per unit of its
    colour (a power, colour or world edit only rescales it, a move re-lights it alone), and an emissive mesh's
    clusters together with their colours (they change only with the geometry and materials), as do the lights past
    MAX_UNIT_GROUPS. Keys from shadows.light_keys (a light's record without its colour and its packed views)."""
    records = shadows.buffers.lights
    alone, shared = [], []
    for i, emitter in enumerate(emitter_records(records)):
        (shared if emitter or len(alone) >= MAX_UNIT_GROUPS else alone).append(i)
    groups = [LightGroup(shadows.light_keys[i], [i], True) for i in alone]
    if shared:
        key = hash_parts([shadows.light_keys[i] for i in shared], records["color_type"][shared])
        groups.append(LightGroup(key, shared, False))
    return groups


def render_direct_light(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas, material_lut=None, sky=None,
                        prior: dict | None = None, relight: Relight | None = None) -> dict:
    """{"diffuse": Diffuse Direct (irradiance/π), "glossy": Glossy Direct} for every G-buffer pixel, (H, W, 3)
    float32 as gl/bind.read_texture gives a texture. `material_lut`: the materials' Principled table
    (direct/geometry.MaterialTextures.lut); None for G-buffers with no camera (the surface atlas), whose Glossy
    Direct is 0. `sky`: the sky light's shares (direct/sky.render_sky_visibility's texture; None: computed here).
    The lights are lit by groups (light_groups) and summed; "groups" keeps each group's images by key, and a group
    whose key `prior` (an earlier output for the same G-buffer, shadow settings and material table) holds is not lit
    again ("relit": the groups that were); with `relight` instead, an unchanged group is lit again where an object's
    move can change it ("relit_pixels": the share of pixel × group runs that were)."""
    groups = light_groups(shadows)
    kept = prior["groups"] if prior is not None else {}
    images = {g.key: kept[g.key] if g.key in kept else None for g in groups}
    todo = [g for g in groups if images[g.key] is None]
    masks = _relight_masks(shadows, todo, relight)
    if todo:
        textures = [ctx.texture(gbuffer.size, 4, dtype="f4") for _ in range(2)]
        prog = programs.compute("direct/light.glsl", shadows.defines)
        unit_records = shadows.buffers.lights.copy()
        unit_records["color_type"][:, :3] = 1.0
        unit_ssbo = ssbo(ctx, unit_records)
        for g in todo:
            # The inputs again for each group: the previous group's read-back re-bound texture units.
            unit = bind_inputs(prog, gbuffer, shadows, material_lut)
            if sky is not None:
                bind_samplers(prog, "u_sky_shares", [sky], unit)
            set_uniform(prog, "u_sky_cached", sky is not None)
            (unit_ssbo if g.unit else shadows.light_ssbo).bind_to_storage_buffer(0)
            images[g.key] = _render_group(ctx, prog, gbuffer, g.lights, textures, masks.get(g.key))
        for obj in textures + [unit_ssbo]:
            obj.release()
    out = {"diffuse": 0.0, "glossy": 0.0, "groups": images, "relit": len(todo)}
    if masks:
        out["relit_pixels"] = (sum(m.share for m in masks.values()) + len(todo) - len(masks)) / len(todo)
    for g in groups:  # in the groups' order, so that a cold render sums alike
        scale = shadows.buffers.lights["color_type"][g.lights[0], :3] if g.unit else 1.0
        for name, image in zip(("diffuse", "glossy"), images[g.key]):
            out[name] = out[name] + image * np.asarray(scale, np.float32)
    h, w = gbuffer.size[1], gbuffer.size[0]
    for name in ("diffuse", "glossy"):
        out[name] = np.broadcast_to(np.asarray(out[name], np.float32), (h, w, 3)).copy()
    return out


@dataclass
class _Mask:
    """A group's masked run: its earlier images, the redrawn views its lights own (CHANGED_VIEW records) and the
    moved pixels; `share` of the pixels it lit again (set by _render_group)."""
    prior: tuple
    changed: np.ndarray
    pixels: tuple
    share: float = 1.0


CHANGED_VIEW = np.dtype([("index", "<i4", 4), ("rect", "<f4", 4)])  # direct/light.glsl ChangedView


def _relight_masks(shadows: ShadowAtlas, todo: list, relight: Relight | None) -> dict:
    """group key → _Mask for each group of `todo` that `relight` lets keep its unchanged pixels: its key (lights and
    views) as before, and no sky light (its shares come from the sky_visibility pass, lit again after a move)."""
    if relight is None:
        return {}
    kept = relight.prior["groups"]
    owner = np.asarray(shadows.buffers.view_lights or [], np.int64)
    tiles = shadows.maps.tiles
    kinds = shadows.buffers.lights["color_type"][:, 3].astype(int)
    masks = {}
    for g in todo:
        if g.key not in kept or any(kinds[i] == lb.LIGHT_SKY for i in g.lights):
            continue
        mine = sorted((v, rect or tiles[v]) for v, rect in relight.redrawn if owner[v] in g.lights)
        changed = np.zeros(len(mine), CHANGED_VIEW)
        for row, (v, (x, y, w, h)) in zip(changed, mine):
            row["index"] = (v, owner[v], 0, 0)
            row["rect"] = (x, y, x + w, y + h)
        masks[g.key] = _Mask(kept[g.key], changed, relight.pixels)
    return masks


def _render_group(ctx, prog, gbuffer: GBuffer, lights: list, textures: list, mask: _Mask | None = None) -> tuple:
    """One group's Diffuse Direct and Glossy Direct, drawn into `textures` and read back; `prog` has its inputs and
    light records bound. With `mask`, only the pixels an object's move can change are lit, the others kept."""
    for binding, tex in enumerate(textures):
        tex.bind_to_image(binding, read=False, write=True)
    members = ssbo(ctx, np.asarray(lights, np.int32))
    members.bind_to_storage_buffer(9)
    changed = ssbo(ctx, mask.changed if mask is not None else np.zeros(0, CHANGED_VIEW))
    changed.bind_to_storage_buffer(10)
    set_uniforms(prog, {"u_group_count": len(lights), "u_masked": mask is not None,
                        "u_changed_count": 0 if mask is None else len(mask.changed),
                        "u_moved_pixels": (0, 0, 0, 0) if mask is None else tuple(int(c) for c in mask.pixels)})
    dispatch(prog, gbuffer.size, local=8)
    members.release()
    changed.release()
    if mask is None:
        return tuple(read_texture(tex, 3) for tex in textures)
    new = [read_texture(tex, 4) for tex in textures]
    lit = new[0][..., 3:] > 0.5
    mask.share = float(lit.mean())
    return tuple(np.where(lit, image[..., :3], old) for image, old in zip(new, mask.prior))


def bind_inputs(prog, gbuffer: GBuffer, shadows: ShadowAtlas, material_lut) -> int:
    """The G-buffer, the material table and the lights for direct/light.glsl; returns the next free texture unit."""
    unit = 0
    for name in ("position", "normal", "geo_normal", "glossy", "specular"):
        unit = bind_samplers(prog, f"u_{name}", [gbuffer.textures[name]], unit)
    if material_lut is not None:
        unit = bind_samplers(prog, "u_material_lut", [material_lut], unit)
    unit = bind_lights(prog, shadows, unit)
    w, h = gbuffer.size
    set_uniforms(prog, {"u_size": (w, h), "u_glossy_enabled": material_lut is not None, "u_eye": tuple(gbuffer.eye),
                        "u_forward": tuple(gbuffer.forward), "u_ortho": bool(gbuffer.ortho)})
    return unit
