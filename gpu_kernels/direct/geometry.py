# SPDX-License-Identifier: GPL-3.0-or-later
"""Geometry and material inputs of every raster pass: the interleaved vertex buffer grouped by material, the
material textures, and drawing one material range at a time with its uniforms (common/materials.glsl)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.principled import material_lut, transport_albedo
from ..gl.bind import set_uniform
from ..scene import Scene

LUT_UNIT = 15  # the material table's texture unit: above every pass's own samplers (GL guarantees 16 units)


# The vertex buffer's layout (upload_geometry: position, shading normal, UV, geometric normal, material index; 12
# float32 per corner) as the moderngl formats of the attributes a program reads.
POSITION_ONLY = "3f 36x"
POSITION_UV = "3f 12x 2f 16x"
SURFACE = "3f 3f 2f 3f 4x"              # in_position, in_normal, in_uv, in_geo_normal
SURFACE_MATERIAL = "3f 3f 2f 3f 1f"     # the same and in_material


@dataclass
class GeometryBuffers:
    vbo: object
    vao_full: object  # position, normal, uv, geometric normal
    vao_depth: object  # position only (shadow maps)
    ranges: list  # (material index, first vertex, vertex count), triangles grouped by material

    def release(self):
        for obj in (self.vao_full, self.vao_depth, self.vbo):
            obj.release()


def upload_geometry(ctx, programs, scene: Scene) -> GeometryBuffers:
    """Interleave corners (position, normal, uv, geometric normal, material index) grouped by material into one
    VBO."""
    order = np.argsort(scene.material_index, kind="stable")
    pos = scene.positions[order].astype(np.float32)
    nrm = scene.normals[order].astype(np.float32)
    uvs = scene.uvs[order].astype(np.float32)
    geo = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    geo /= np.maximum(np.linalg.norm(geo, axis=1, keepdims=True), 1e-30)
    geo = np.repeat(geo[:, None, :], 3, axis=1)
    mats = scene.material_index[order]
    material = np.repeat(mats.astype(np.float32)[:, None, None], 3, axis=1)
    data = np.concatenate([pos, nrm, uvs, geo, material], axis=2).astype(np.float32)  # (T, 3, 12)
    vbo = ctx.buffer(np.ascontiguousarray(data).tobytes() or b"\0" * 48)
    gbuf = programs.raster("direct/gbuffer.glsl")
    depth = programs.raster("direct/shadow_depth.glsl")
    vao_full = ctx.vertex_array(gbuf, [(vbo, SURFACE, "in_position", "in_normal", "in_uv", "in_geo_normal")])
    vao_depth = ctx.vertex_array(depth, [(vbo, POSITION_ONLY, "in_position")])
    ranges = []
    if len(mats):
        starts = np.flatnonzero(np.r_[True, mats[1:] != mats[:-1]])
        ends = np.r_[starts[1:], len(mats)]
        ranges = [(int(mats[s]), int(s) * 3, int(e - s) * 3) for s, e in zip(starts, ends)]
    return GeometryBuffers(vbo, vao_full, vao_depth, ranges)


class MaterialTextures:
    """What the material uniforms sample: the scene's images (indexable like Scene.textures) and the materials'
    Principled table (common/principled.py: material_lut) with each material's transport albedo terms
    (principled.transport_albedo: (scale, offset) rows, (M, 2, 3)); `colors`: base_colors, and the storage buffer
    holding them (`colors_ssbo`, lpv/inject.glsl)."""

    def __init__(self, images: list, lut, transport: np.ndarray, colors: np.ndarray, colors_ssbo=None):
        self.images, self.lut, self.transport = images, lut, transport
        self.colors, self.colors_ssbo = colors, colors_ssbo

    def __len__(self):
        return len(self.images)

    def __getitem__(self, i):
        return self.images[i]

    def release(self):
        for t in self.images + [self.lut] + ([self.colors_ssbo] if self.colors_ssbo is not None else []):
            t.release()


def base_colors(scene: Scene, images: int) -> np.ndarray:
    """(max(M, 1), 4) float32: per material the colour its base colour texture is multiplied by in the RSM's
    injection (lpv/inject.glsl texel_albedo) — its base colour, or 1 where a texture gives the colour (the RSM
    holds the texture's) — as bind_material colours a draw; w = 1 for a metal (its albedo is not linear in the
    colour: common/principled.glsl principled_glossy), else 0."""
    out = np.zeros((max(len(scene.materials), 1), 4), np.float32)
    out[:, :3] = 0.8  # bind_material's colour for a material index that names none
    for i, m in enumerate(scene.materials):
        out[i, :3] = 1.0 if 0 <= m.base_color_texture < images else m.base_color[:3]
        out[i, 3] = float(m.metallic != 0)
    return out


def upload_textures(ctx, scene: Scene) -> MaterialTextures:
    """Material textures as float RGBA, bilinear without mipmaps (Cycles' CPU 'Linear' filtering), and the
    Principled table, filtered linearly along μ."""
    import moderngl

    out = []
    for tex in scene.textures:
        px = np.ascontiguousarray(tex.pixels, np.float32)
        h, w = px.shape[:2]
        t = ctx.texture((w, h), 4, px.tobytes(), dtype="f4")
        f = moderngl.NEAREST if tex.interpolation == "Closest" else moderngl.LINEAR
        t.filter = (f, f)
        t.repeat_x = t.repeat_y = tex.extension == "REPEAT"
        out.append(t)
    lut_rows = material_lut(scene.materials)
    lut = ctx.texture((lut_rows.shape[1], lut_rows.shape[0]), 4, np.ascontiguousarray(lut_rows).tobytes(), dtype="f4")
    lut.filter = (moderngl.LINEAR, moderngl.LINEAR)
    lut.repeat_x = lut.repeat_y = False
    terms = np.array([transport_albedo(m)[:2] for m in scene.materials] or [((1.0,) * 3, (0.0,) * 3)], np.float32)
    colors = base_colors(scene, len(out))
    return MaterialTextures(out, lut, terms, colors, ctx.buffer(colors.tobytes()))


def bind_material(prog, scene: Scene, mat_index: int, textures: MaterialTextures) -> None:
    """Set the material uniforms of common/materials.glsl for one material (unused ones are skipped)."""
    apply_binding(material_binding(prog, scene, mat_index, textures))


def material_binding(prog, scene: Scene, mat_index: int, textures: MaterialTextures) -> tuple:
    """What bind_material sets for one material, resolved once: ([(uniform, value)] of the uniforms `prog` kept,
    [(texture, unit)] to bind). A pass drawing many views binds each material once per view: resolved, a binding
    costs a few value writes instead of a lookup per uniform (the sky's 576 RSM views × a room's materials)."""
    mat = scene.materials[mat_index] if 0 <= mat_index < len(scene.materials) else None
    scale, offset = textures.transport[mat_index if mat else 0]
    use_tex = bool(mat and 0 <= mat.base_color_texture < len(textures))
    values = {"u_base_color": tuple(float(c) for c in (mat.base_color if mat else (0.8, 0.8, 0.8))[:3]),
              "u_roughness": float(mat.roughness) if mat else 0.5, "u_material": mat_index if mat else 0,
              "u_albedo_scale": tuple(float(c) for c in scale), "u_albedo_offset": tuple(float(c) for c in offset),
              "u_material_lut": LUT_UNIT,
              "u_emission": tuple(float(c) for c in (mat.emission if mat else (0, 0, 0))[:3]),
              "u_use_texture": use_tex, "u_base_texture": 0}
    units = [(textures.lut, LUT_UNIT)] if "u_material_lut" in prog else []
    if use_tex:
        units.append((textures[mat.base_color_texture], 0))
    else:
        del values["u_base_texture"]
    return [(prog[name], value) for name, value in values.items() if name in prog], units


def apply_binding(binding: tuple) -> None:
    """Write a material_binding's uniforms and bind its textures."""
    uniforms, units = binding
    for uniform, value in uniforms:
        uniform.value = value
    for texture, unit in units:
        texture.use(location=unit)


def material_batches(scene: Scene, geometry: GeometryBuffers, textures: MaterialTextures) -> list:
    """geometry.ranges merged into draws for a program that reads each vertex's material index (SURFACE_MATERIAL) and
    of a material only its base colour texture: (material index, first vertex, vertex count), consecutive ranges of
    materials without a texture drawn as one (under the first one's uniforms), a textured one alone. The same
    triangles in the same order as draw_by_material draws them, in fewer calls: an RSM draws every shadow view (the
    sky's 576, a lamp's cube) with a room's materials, and llvmpipe pays each call more than its few texels."""
    out = []
    for mat_index, first, count in geometry.ranges:
        mat = scene.materials[mat_index] if 0 <= mat_index < len(scene.materials) else None
        textured = bool(mat and 0 <= mat.base_color_texture < len(textures))
        if out and not textured and not out[-1][3] and out[-1][1] + out[-1][2] == first:
            out[-1] = (out[-1][0], out[-1][1], out[-1][2] + count, False)
        else:
            out.append((mat_index, first, count, textured))
    return [(m, first, count) for m, first, count, _ in out]


def draw_by_material(prog, scene: Scene, geometry: GeometryBuffers, textures: list, vao=None,
                     bindings: dict | None = None, batches: list | None = None) -> None:
    """Draw the geometry one material range at a time with that material's uniforms (common/materials.glsl), or
    (`batches`, material_batches) a draw per batch. `bindings`: material index → material_binding for `prog`, made
    once for many draws (made here if None)."""
    import moderngl

    vao = vao or geometry.vao_full
    for mat_index, first, count in geometry.ranges if batches is None else batches:
        apply_binding(bindings[mat_index] if bindings is not None else
                      material_binding(prog, scene, mat_index, textures))
        vao.render(moderngl.TRIANGLES, vertices=count, first=first)
