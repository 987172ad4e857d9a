# SPDX-License-Identifier: GPL-3.0-or-later
"""Bounce GI: real-time global illumination preview for Blender.

This file is both the Blender extension entry point and the root of the `bounce_gi` Python
package. It must stay import-free: `import bounce_gi.gpu_kernels` runs it outside Blender, and a
test asserts that bpy is not imported then. Blender-only code is imported inside register().
"""


def register():
    """Called by Blender when the extension is enabled."""
    from . import ui

    ui.register()


def unregister():
    """Called by Blender when the extension is disabled, in reverse order of register()."""
    from . import ui

    ui.unregister()
