# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender UI of Bounce GI: settings on the Scene, the render engine (F12, batch and Rendered shading), the
overlay, a 3D-view sidebar panel and a Render Properties panel, the preview operator, Compare with Cycles and
Bake GI to Color Attribute.

Imported only from the extension's register() (it imports bpy). Modules register in the order
below, properties first because the engine, panels and operator read them, and unregister in reverse.
Unregistering (disabling the extension) also shuts the GPU engine down: its worker thread, GL context and
cached passes must not outlive the extension (a re-enabled one would otherwise render from the old cache).
"""
from . import bake_operator, compare_operator, operators, overlay, panel, properties, render_engine

modules = (properties, operators, compare_operator, bake_operator, overlay, render_engine, panel)


def register():
    for module in modules:
        module.register()
    from . import viewport

    viewport.warm_up()


def unregister():
    for module in reversed(modules):
        module.unregister()
    from ..gpu_kernels.engine import shutdown_engine
    from . import draw, viewport

    viewport.close_all()
    draw.release_shader()
    shutdown_engine()
