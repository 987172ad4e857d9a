# SPDX-License-Identifier: GPL-3.0-or-later
"""Light objects → `gpu_kernels.scene.Light`, with Cycles' power conventions (exposure, temperature, node
strength, unnormalised emitters)."""
from __future__ import annotations

import math

import numpy as np

from ...gpu_kernels.scene import Light


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


def read_light(obj, matrix) -> tuple[Light, list]:
    """The Light of a light object instanced at `matrix`, and the warnings about it."""
    data = obj.data
    warnings = []
    color = np.array(data.color[:3], np.float64)
    if getattr(data, "use_temperature", False):
        color = color * np.array(data.temperature_color[:3])
    power = float(data.energy) * 2.0 ** float(getattr(data, "exposure", 0.0))
    if getattr(data, "use_nodes", False) and data.node_tree is not None:
        scale, warn = light_node_scale(data.node_tree)
        color = color * scale
        if warn:
            warnings.append(f"light '{obj.name}': {warn}")
    light = Light(name=obj.name, type=data.type, color=tuple(color), power=power,
                  matrix_world=np.array(matrix, np.float64), cast_shadow=bool(getattr(data, "use_shadow", True)))
    if data.type in ("POINT", "SPOT"):
        light.radius = float(data.shadow_soft_size)
        light.soft_falloff = bool(getattr(data, "use_soft_falloff", True))
        if not getattr(data, "normalize", True):
            # Cycles (scene/light.cpp): without normalisation the emitter radiance is P/π instead of P/(π·area),
            # area = 4πr² (or 4 for r = 0), so the intensity P/(4π) grows by that area.
            light.power *= 4.0 * math.pi * light.radius ** 2 if light.radius > 0 else 4.0
    if data.type == "SPOT":
        light.spot_size = float(data.spot_size)
        light.spot_blend = float(data.spot_blend)
    if data.type == "SUN":
        light.angle = float(data.angle)
    if data.type == "AREA":
        _read_area(light, data, matrix, obj.name, warnings)
    return light, warnings


def _read_area(light: Light, data, matrix, name: str, warnings: list) -> None:
    light.shape, light.size, light.size_y = data.shape, float(data.size), float(data.size_y)
    if getattr(data, "spread", math.pi) < math.pi - 1e-4:
        warnings.append(f"area light '{name}' has spread < 180°; it is lit as a full-spread light")
    if not getattr(data, "normalize", True):
        # Without normalisation, Cycles does not divide the power by the area: radiance = P/π per m².
        m = np.asarray(matrix, np.float64)
        sx, sy = np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])
        side_y = light.size if light.shape in ("SQUARE", "DISK") else light.size_y
        area = light.size * side_y * sx * sy * (math.pi / 4 if light.shape in ("DISK", "ELLIPSE") else 1.0)
        light.power *= area
