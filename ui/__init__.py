# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender UI of Bounce GI: settings on the Scene, a 3D-view sidebar panel, the preview operator.

Imported only from the extension's register() (it imports bpy). Modules register in the order
below, properties first because the panel and operator read them, and unregister in reverse.
"""
from . import operators, panel, properties

modules = (properties, operators, panel)


def register():
    for module in modules:
        module.register()


def unregister():
    for module in reversed(modules):
        module.unregister()
