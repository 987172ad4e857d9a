# SPDX-License-Identifier: GPL-3.0-or-later
"""The overlay: the live GI drawn over the 3D viewport in Solid and Material Preview shading (operator
`bounce_gi.toggle_overlay`, in the sidebar).

On: one ViewportFeed (viewport.py) fed by a depsgraph_update_post handler, and one POST_VIEW draw handler per 3D
view that draws the newest result depth-tested against the scene, pulled a hair toward the camera so it wins over
Blender's own copy of the same surfaces. Off — or the extension disabled, or another file loaded — removes both
handlers and frees every GPU resource. Nothing is stored in the .blend.
"""
from __future__ import annotations

import bpy

from .preview import tag_redraw_all
from .viewport import ViewportFeed, close_all, region_view

DEPTH_PULL = 1e-5  # clip-space w fraction: above depth-buffer precision at the surfaces, far below any gap


class OverlayState:
    feed = None  # ViewportFeed while the overlay is on
    draw_handle = None


state = OverlayState()


def is_on() -> bool:
    return state.feed is not None


def draw_overlay() -> None:
    feed, context = state.feed, bpy.context
    if feed is None or feed.session.drawing is None or context.region_data is None:
        return
    if context.space_data.shading.type == "RENDERED":
        return  # Rendered shading draws the same result itself
    feed.session.drawing.draw(region_view(context.region_data), context.scene.bounce_gi.display_mode, DEPTH_PULL)


@bpy.app.handlers.persistent
def on_depsgraph_update(_scene, depsgraph) -> None:
    if state.feed is not None:
        state.feed.update(depsgraph)


@bpy.app.handlers.persistent
def on_load_pre(*_args) -> None:
    """Another file is loading: the old scene's results must not be drawn over the new one, by the overlay or by
    a Rendered 3D view (its engine makes a new feed on its next view_update)."""
    disable()
    close_all()


def enable(depsgraph) -> None:
    if state.feed is not None:
        return
    state.feed = ViewportFeed(on_update=lambda: tag_redraw_all(("VIEW_3D",)))
    state.draw_handle = bpy.types.SpaceView3D.draw_handler_add(draw_overlay, (), "WINDOW", "POST_VIEW")
    bpy.app.handlers.depsgraph_update_post.append(on_depsgraph_update)
    state.feed.update(depsgraph, first=True)


def disable() -> None:
    if state.draw_handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(state.draw_handle, "WINDOW")
        state.draw_handle = None
    if on_depsgraph_update in bpy.app.handlers.depsgraph_update_post:
        bpy.app.handlers.depsgraph_update_post.remove(on_depsgraph_update)
    if state.feed is not None:
        state.feed.close()
        state.feed = None
    tag_redraw_all(("VIEW_3D",))


class BOUNCE_GI_OT_toggle_overlay(bpy.types.Operator):
    """Draw Bounce GI's live global illumination over the viewport in Solid and Material Preview shading"""

    bl_idname = "bounce_gi.toggle_overlay"
    bl_label = "GI Overlay"
    bl_options = {"REGISTER"}  # no Undo step: nothing in the file changes

    def execute(self, context):
        if is_on():
            disable()
            return {"FINISHED"}
        try:
            enable(context.evaluated_depsgraph_get())
        except Exception as ex:  # one line for the user, nothing left behind
            disable()
            self.report({"ERROR"}, f"Bounce GI overlay could not start: {type(ex).__name__}: {ex}")
            return {"CANCELLED"}
        if state.feed.session.stats.error:
            self.report({"WARNING"}, state.feed.session.stats.error)
        return {"FINISHED"}


classes = (BOUNCE_GI_OT_toggle_overlay,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.app.handlers.load_pre.append(on_load_pre)


def unregister():
    disable()
    if on_load_pre in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(on_load_pre)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
