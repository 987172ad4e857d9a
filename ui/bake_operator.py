# SPDX-License-Identifier: GPL-3.0-or-later
"""The Bake GI to Color Attribute operator (`bounce_gi.bake_color_attribute`); its steps are in bake.py.

Interactively (invoke) it is modal: the GPU job runs on the engine's thread, a window-manager timer polls it with
the elapsed time in the status bar, and Esc cancels (nothing is written). In background mode and from scripts
(execute) it blocks. The attributes are written in one go when the job is done, inside the operator, so one Undo
step takes the whole bake back; a failure is one ERROR report and writes nothing.
"""
import bpy
from bpy.props import BoolProperty
from bpy.types import Operator

from . import bake, preview
from .operators import set_status
from .preview import PreviewError

POLL_INTERVAL = 0.1


class BOUNCE_GI_OT_bake_color_attribute(Operator):
    """Bake Bounce GI's light into the colour attribute "BounceGI" of every visible mesh, per vertex (by default
    the indirect diffuse light without albedo, as Cycles' Diffuse bake with only Indirect)"""

    bl_idname = "bounce_gi.bake_color_attribute"
    bl_label = "Bake GI to Color Attribute"
    bl_options = {"REGISTER", "UNDO"}

    selected_only: BoolProperty(name="Selected Only", description="Bake only the selected meshes", default=False)
    include_direct: BoolProperty(name="Include Direct", description="Add the direct light", default=False)
    include_albedo: BoolProperty(name="Include Albedo", description="Multiply by the diffuse colour",
                                 default=False)

    _pending = None
    _timer = None

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.mode == "OBJECT"

    def _fail(self, message: str):
        self.report({"ERROR"}, message)
        return {"CANCELLED"}

    def execute(self, context):
        """Blocking: background mode, scripts, tests."""
        try:
            summary = bake.finish_bake(bake.start_bake(context, self.selected_only), self.include_direct,
                                       self.include_albedo)
        except PreviewError as ex:
            return self._fail(str(ex))
        self._done(summary)
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        try:
            self._pending = bake.start_bake(context, self.selected_only)
        except PreviewError as ex:
            return self._fail(str(ex))
        wm = context.window_manager
        self._timer = wm.event_timer_add(POLL_INTERVAL, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self._pending.future.cancel()  # a job already running finishes on the GPU thread; its result is dropped
            self._cleanup(context)
            self.report({"WARNING"}, "Bounce GI: bake cancelled, nothing written")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not self._pending.future.done():
            vertices = sum(t.vertex_count for t in self._pending.targets)
            set_status(context, f"Bounce GI: baking {vertices} vertices of {len(self._pending.targets)} meshes "
                                f"({self._pending.method}) {self._pending.elapsed():.1f} s   Esc: cancel")
            return {"PASS_THROUGH"}
        self._cleanup(context)
        try:
            summary = bake.finish_bake(self._pending, self.include_direct, self.include_albedo)
        except PreviewError as ex:
            return self._fail(str(ex))
        self._done(summary)
        return {"FINISHED"}

    def cancel(self, context):
        self._cleanup(context)

    def _cleanup(self, context):
        if self._timer is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        set_status(context, None)
        preview.tag_redraw_all(("VIEW_3D",))

    def _done(self, summary: dict) -> None:
        for name in summary["skipped"]:
            self.report({"WARNING"}, f"Bounce GI bake: {name}'s modifiers change its vertex count; left out")
        for text in summary["warnings"][:1]:
            self.report({"WARNING"}, f"Bounce GI: {text}")
        self.report({"INFO"}, f"Bounce GI: baked {summary['vertices']} vertices of {summary['meshes']} mesh(es) "
                              f"into '{bake.ATTRIBUTE}' ({summary['method']}) in {summary['seconds']:.2f} s")


classes = (BOUNCE_GI_OT_bake_color_attribute,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
