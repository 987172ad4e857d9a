# SPDX-License-Identifier: GPL-3.0-or-later
"""Materials: Blender node materials reduced to what the pipeline understands (gpu_kernels.scene.Material), and
the image textures they use (gpu_kernels.scene.Texture).

Understood: Principled BSDF and Diffuse BSDF base colour (constant, or an Image Texture through UV), emission
colour × strength; for Principled also roughness, metallic, IOR, Specular IOR Level and Tint, transmission weight,
coat (weight, roughness, IOR, tint) and the distribution, which set its layers' albedo (gpu_kernels/common/
principled.py); a lone Emission shader. Anything else falls back to the material's
viewport display colour and the returned warning names the material.
"""
from __future__ import annotations

import numpy as np

from ...gpu_kernels.scene import Material, Texture


class MaterialTable:
    """The Scene's materials in first-use order (the default first) and their textures; each Blender material is
    read once, keyed by its original name, and the warning reading it gave is appended to `warnings`."""

    def __init__(self, warnings: list):
        self.warnings = warnings
        self.materials: list[Material] = [Material("Default", (0.8, 0.8, 0.8))]  # 0: triangles without a material
        self.textures: list[Texture] = []
        self.material_ids: dict = {}  # original material name -> index in `materials`
        self.image_ids: dict = {}  # image name -> index in `textures`

    def index(self, material) -> int:
        """Index in `materials` of a bpy material (0 for None), reading it the first time it is seen."""
        if material is None:
            return 0
        key = material.original.name if hasattr(material, "original") else material.name
        if key not in self.material_ids:
            mat, warn = read_material(material, self.textures, self.image_ids)
            if warn:
                self.warnings.append(warn)
            self.material_ids[key] = len(self.materials)
            self.materials.append(mat)
        return self.material_ids[key]


def _output_surface_node(tree):
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    active = [n for n in outputs if n.is_active_output and n.target in ("ALL", "CYCLES")]
    out = (active or [n for n in outputs if n.target in ("ALL", "CYCLES")] or outputs or [None])[0]
    if out is None or not out.inputs["Surface"].is_linked:
        return None
    return out.inputs["Surface"].links[0].from_node


def _srgb_to_linear(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def read_image(image) -> np.ndarray:
    """Image pixels as scene-linear float RGBA (H, W, 4), rows bottom-up like Blender's."""
    w, h = image.size
    if w == 0 or h == 0:
        raise ValueError(f"image '{image.name}' has no pixels (missing file?)")
    px = np.empty(w * h * image.channels, np.float32)
    image.pixels.foreach_get(px)
    px = px.reshape(h, w, image.channels)
    if image.channels < 4:
        px = np.concatenate([px, np.ones((h, w, 4 - image.channels), np.float32)], axis=2)[..., :4]
        if image.channels == 1:
            px[..., 1] = px[..., 2] = px[..., 0]
    # `image.pixels` holds byte images in their own colour space (not linearised); float images are linear.
    space = image.colorspace_settings.name
    if not image.is_float and space in ("sRGB", "sRGB EOTF"):
        px[..., :3] = _srgb_to_linear(px[..., :3])
    elif not image.is_float and space not in ("Non-Color", "Linear Rec.709", "Linear", "Raw"):
        raise ValueError(f"image '{image.name}' uses colour space '{space}', which is not supported")
    return px.astype(np.float32)


def _color_input(socket, textures, image_ids):
    """(rgb tuple, texture index or -1, warning or None) for a colour socket."""
    if not socket.is_linked:
        return tuple(socket.default_value[:3]), -1, None
    node = socket.links[0].from_node
    if node.bl_idname == "ShaderNodeTexImage" and node.image is not None:
        vec = node.inputs["Vector"]
        if vec.is_linked and vec.links[0].from_node.bl_idname != "ShaderNodeUVMap":
            return (0.8, 0.8, 0.8), -1, f"texture '{node.image.name}' uses a non-UV mapping"
        key = node.image.name
        if key not in image_ids:
            try:
                pixels = read_image(node.image)
            except ValueError as exc:
                return (0.8, 0.8, 0.8), -1, str(exc)
            image_ids[key] = len(textures)
            textures.append(Texture(key, pixels, interpolation=node.interpolation, extension=node.extension))
        return (1.0, 1.0, 1.0), image_ids[key], None
    if node.bl_idname == "ShaderNodeRGB":
        return tuple(node.outputs[0].default_value[:3]), -1, None
    return (0.8, 0.8, 0.8), -1, f"input '{socket.name}' is driven by a {node.bl_idname} node"


def read_material(material, textures: list, image_ids: dict) -> tuple[Material, str | None]:
    """Return (Material, warning or None); on unsupported node trees, the viewport display colour."""
    fallback = Material(material.name, tuple(material.diffuse_color[:3]), roughness=float(material.roughness),
                        metallic=float(material.metallic))
    tree = material.node_tree if getattr(material, "use_nodes", True) else None
    if tree is None:
        return fallback, None
    node = _output_surface_node(tree)
    if node is None:
        return Material(material.name, (0.0, 0.0, 0.0)), None  # no surface: black, like Cycles
    kind = node.bl_idname
    if kind == "ShaderNodeBsdfDiffuse":
        color, tex, warn = _color_input(node.inputs["Color"], textures, image_ids)
        if warn:
            return fallback, f"material '{material.name}' falls back to its viewport colour: {warn}"
        return Material(material.name, color, tex, roughness=1.0), None
    if kind == "ShaderNodeBsdfPrincipled":
        return _read_principled(material, node, textures, image_ids, fallback)
    if kind == "ShaderNodeEmission":
        strength = float(node.inputs["Strength"].default_value)
        emission = np.array(node.inputs["Color"].default_value[:3]) * strength
        return Material(material.name, (0.0, 0.0, 0.0), emission=tuple(emission)), None
    return fallback, f"material '{material.name}' uses {node.bl_idname}; showing its viewport colour"


def _value(ins, name, default):
    """An unlinked input's value (a tuple for colours), or `default` on Blender versions without the input."""
    if name not in ins:
        return default
    value = ins[name].default_value
    return tuple(value[:3]) if hasattr(value, "__len__") else float(value)


def _read_principled(material, node, textures, image_ids, fallback) -> tuple[Material, str | None]:
    color, tex, warn = _color_input(node.inputs["Base Color"], textures, image_ids)
    if warn:
        return fallback, f"material '{material.name}' falls back to its viewport colour: {warn}"
    ins = node.inputs
    emission = np.array(ins["Emission Color"].default_value[:3]) * float(ins["Emission Strength"].default_value)
    mat = Material(material.name, color, tex, tuple(emission), _value(ins, "Roughness", 0.5),
                   _value(ins, "Metallic", 0.0), specular_layer=True, ior=_value(ins, "IOR", 1.5),
                   specular_ior_level=_value(ins, "Specular IOR Level", 0.5),
                   specular_tint=_value(ins, "Specular Tint", (1.0, 1.0, 1.0)),
                   transmission=_value(ins, "Transmission Weight", 0.0), coat_weight=_value(ins, "Coat Weight", 0.0),
                   coat_roughness=_value(ins, "Coat Roughness", 0.03), coat_ior=_value(ins, "Coat IOR", 1.5),
                   coat_tint=_value(ins, "Coat Tint", (1.0, 1.0, 1.0)),
                   multiscatter=getattr(node, "distribution", "MULTI_GGX") != "GGX")
    linked = [n for n in ("Roughness", "Metallic", "IOR", "Specular IOR Level", "Specular Tint", "Transmission Weight",
                          "Coat Weight", "Emission Color", "Emission Strength") if n in ins and ins[n].is_linked]
    notes = []
    if linked:
        notes.append(f"{', '.join(linked)} driven by nodes (their unlinked values are used)")
    if _value(ins, "Sheen Weight", 0.0) > 0.0:
        notes.append("sheen is not modelled")
    if mat.transmission > 0.0:
        notes.append("transmission is shown as absorbed (no refraction)")
    warn = f"material '{material.name}': " + "; ".join(notes) if notes else None
    return mat, warn
