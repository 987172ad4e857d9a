# SPDX-License-Identifier: GPL-3.0-or-later
"""The Render Preview operator: extract on the main thread, render on the engine's thread.

Interactively (invoke) it is modal: a window-manager timer polls the engine's Future, so the UI
stays responsive and Esc stops waiting. From scripts and in background mode (execute) it blocks
until the image is written, because modal operators never run there. Either way, failures are
reported as one line and the operator returns CANCELLED; tracebacks go to the console only.
"""
import bpy
from bpy.types import Operator

from . import preview
from .preview import PreviewError

# How often the modal operator checks the Future. 0.1 s keeps the elapsed-time text lively
# without waking Blender more than needed.
POLL_INTERVAL = 0.1


def set_status(context, text):
    """Show progress in the status bar (None clears it). The workspace may be gone in odd states."""
    workspace = getattr(context, "workspace", None)
    if workspace is not None:
        workspace.status_text_set(text)


def _report_done(op, report) -> None:
    total = report.timings.get("total", report.wall_seconds)
    written = f"; passes written to {report.output}" if report.output else ""
    op.report({"INFO"}, f"Bounce GI: {report.width}x{report.height} {report.method} in {total * 1000:.0f} ms "
                        f"(waited {report.wall_seconds:.2f} s){written}")
    if report.warnings:
        more = f" (+{len(report.warnings) - 1} more in the panel)" if len(report.warnings) > 1 else ""
        op.report({"WARNING"}, f"Bounce GI: {report.warnings[0]}{more}")


def _show_in_image_editors(context) -> None:
    """Put the preview in Image Editors that show nothing; never replace what the user picked."""
    img = bpy.data.images.get(preview.IMAGE_NAME)
    for window in context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "IMAGE_EDITOR" and area.spaces.active.image is None:
                area.spaces.active.image = img


class BOUNCE_GI_OT_render_preview(Operator):
    """Render the active camera with Bounce GI into the image 'Bounce GI Preview'"""

    bl_idname = "bounce_gi.render_preview"
    bl_label = "Render Preview"
    # No UNDO: the result is a runtime image, and an undo step would snapshot its pixels.
    bl_options = {"REGISTER"}

    _pending = None

    @classmethod
    def poll(cls, context):
        if preview.state.busy:
            cls.poll_message_set("A Bounce GI preview is already rendering")
            return False
        return context.scene is not None

    def _fail(self, message: str):
        preview.state.last_error = message
        self.report({"ERROR"}, message)
        return {"CANCELLED"}

    def execute(self, context):
        """Blocking path for scripts, tests and background mode."""
        try:
            pending = preview.start_render(context.scene, context.evaluated_depsgraph_get())
            report = preview.finish_render(pending)
        except PreviewError as ex:
            return self._fail(str(ex))
        _report_done(self, report)
        return {"FINISHED"}

    def invoke(self, context, event):
        try:
            self._pending = preview.start_render(context.scene, context.evaluated_depsgraph_get())
        except PreviewError as ex:
            return self._fail(str(ex))
        wm = context.window_manager
        preview.state.busy = True
        preview.state.timer = wm.event_timer_add(POLL_INTERVAL, window=context.window)
        wm.modal_handler_add(self)
        self._progress(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            # A running GPU job cannot be interrupted; cancel() only drops it if not yet started.
            # Either way we stop waiting and ignore its result.
            self._pending.future.cancel()
            self._cleanup(context)
            preview.state.last_error = "Cancelled"
            self.report({"WARNING"}, "Bounce GI: stopped waiting for the preview")
            return {"CANCELLED"}
        if event.type != "TIMER":
            # Let the user keep working while the engine renders.
            return {"PASS_THROUGH"}
        if not self._pending.future.done():
            self._progress(context)
            return {"PASS_THROUGH"}

        self._cleanup(context)
        try:
            report = preview.finish_render(self._pending)
        except PreviewError as ex:
            return self._fail(str(ex))
        _show_in_image_editors(context)
        _report_done(self, report)
        return {"FINISHED"}

    def cancel(self, context):
        # Blender calls this when the window closes or the file is reloaded mid-render.
        self._cleanup(context)

    def _progress(self, context):
        p = self._pending
        set_status(context, f"Bounce GI: rendering {p.width}x{p.height} ({p.method}) "
                             f"{p.elapsed():.1f} s   Esc: stop waiting")
        preview.tag_redraw_all(("VIEW_3D",))

    def _cleanup(self, context):
        if preview.state.timer is not None:
            context.window_manager.event_timer_remove(preview.state.timer)
            preview.state.timer = None
        preview.state.busy = False
        set_status(context, None)
        preview.tag_redraw_all()


classes = (BOUNCE_GI_OT_render_preview,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.app.handlers.load_post.append(preview.forget_last_render)


def unregister():
    # Disabling the extension mid-render: Blender drops the modal handler with the class, so the
    # timer and the busy flag would leak; clear them here.
    if preview.state.timer is not None:
        try:
            bpy.context.window_manager.event_timer_remove(preview.state.timer)
        except (ReferenceError, AttributeError, RuntimeError):
            pass
        preview.state.timer = None
    preview.state.busy = False
    if preview.forget_last_render in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(preview.forget_last_render)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
