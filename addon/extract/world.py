# SPDX-License-Identifier: GPL-3.0-or-later
"""The world: a constant radiance (`gpu_kernels.scene.World`) read from the Background node or viewport colour."""
from __future__ import annotations

import numpy as np

from ...gpu_kernels.scene import World


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


def read_world(scene, warnings: list) -> World:
    """The scene's world (black without one); a warning about it is appended to `warnings`."""
    world = scene.world
    if world is None:
        return World((0.0, 0.0, 0.0))
    color, warn = world_color(world)
    if warn:
        warnings.append(warn)
    return World(tuple(color))
