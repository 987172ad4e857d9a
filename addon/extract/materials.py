"""Reduce Blender node materials to what the pipeline understands (gpu_kernels.scene.Material).

Understood: Principled BSDF and Diffuse BSDF base colour (constant, or an Image Texture through UV), emission
colour × strength, roughness, metallic; a lone Emission shader. Anything else falls back to the material's
viewport display colour and the returned warning names the material.
"""
from __future__ import annotations

import numpy as np

from ...gpu_kernels.scene import Material, Texture


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
        color, tex, warn = _color_input(node.inputs["Base Color"], textures, image_ids)
        if warn:
            return fallback, f"material '{material.name}' falls back to its viewport colour: {warn}"
        ins = node.inputs
        rough = float(ins["Roughness"].default_value)
        metal = float(ins["Metallic"].default_value)
        emission = np.array(ins["Emission Color"].default_value[:3]) * float(ins["Emission Strength"].default_value)
        warn = None
        if abs(float(ins["IOR"].default_value) - 1.5) > 1e-3 or abs(float(ins["Specular IOR Level"].default_value) - 0.5) > 1e-3:
            warn = (f"material '{material.name}': the diffuse share is modelled for IOR 1.5 and Specular IOR Level 0.5; "
                    "other values are approximated by it")
        return Material(material.name, color, tex, tuple(emission), rough, metal, specular_layer=True), warn
    if kind == "ShaderNodeEmission":
        strength = float(node.inputs["Strength"].default_value)
        emission = np.array(node.inputs["Color"].default_value[:3]) * strength
        return Material(material.name, (0.0, 0.0, 0.0), emission=tuple(emission)), None
    return fallback, f"material '{material.name}' uses {node.bl_idname}; showing its viewport colour"


def world_color(world) -> tuple[tuple, str | None]:
    """Constant world radiance (colour × strength) and a warning if the world is more than a constant."""
    tree = world.node_tree if getattr(world, "use_nodes", False) else None
    if tree is None:
        return tuple(world.color[:3]), None
    outs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld" and n.is_active_output] or \
        [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
    if not outs or not outs[0].inputs["Surface"].is_linked:
        return (0.0, 0.0, 0.0), None
    node = outs[0].inputs["Surface"].links[0].from_node
    if node.bl_idname != "ShaderNodeBackground":
        return tuple(world.color[:3]), f"world uses {node.bl_idname}; using its viewport colour"
    color = node.inputs["Color"]
    strength = float(node.inputs["Strength"].default_value)
    if color.is_linked:
        return tuple(world.color[:3]), "world colour is driven by nodes (e.g. a sky texture); using its viewport colour"
    return tuple(np.array(color.default_value[:3]) * strength), None


def light_node_scale(tree) -> tuple[np.ndarray, str | None]:
    """RGB factor a light's node tree applies (Emission colour × strength, as Cycles multiplies it in)."""
    outs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputLight" and n.is_active_output] or \
        [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputLight"]
    if not outs or not outs[0].inputs["Surface"].is_linked:
        return np.ones(3), None
    node = outs[0].inputs["Surface"].links[0].from_node
    if node.bl_idname != "ShaderNodeEmission":
        return np.ones(3), f"node tree uses {node.bl_idname}; only the light's colour and power are used"
    color, strength = node.inputs["Color"], node.inputs["Strength"]
    if color.is_linked or strength.is_linked:
        return np.ones(3), "emission driven by nodes; only the light's colour and power are used"
    return np.array(color.default_value[:3], np.float64) * float(strength.default_value), None
