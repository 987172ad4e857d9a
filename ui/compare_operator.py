# SPDX-License-Identifier: GPL-3.0-or-later
"""The Compare with Cycles operator (`bounce_gi.compare_cycles`); its steps are in compare.py.

Interactively (invoke) it is modal: our render runs on the engine's thread while each Cycles seed runs as Blender's
own render job (`bpy.ops.render.render('INVOKE_DEFAULT')`: its progress in the status bar and render window, Esc
stops it); a window-manager timer polls both and starts the next seed. In background mode and from scripts
(execute) it runs the same steps blocking. Either way the render settings are restored exactly (even after Esc or a
failure), failures are one ERROR report, and the operator takes no undo step: it leaves the scene as it was and
only adds runtime images.
"""
import os

import bpy
from bpy.types import Operator

from . import compare, preview
from .operators import set_status
from .preview import PreviewError

POLL_INTERVAL = 0.2


class BOUNCE_GI_OT_compare_cycles(Operator):
    """Render a small Cycles reference of the active camera and compare Bounce GI with it: rel-L1 per pass in the
    panel, ours, Cycles' and the error heat map as images"""

    bl_idname = "bounce_gi.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        if compare.state.busy:
            cls.poll_message_set("A comparison with Cycles is already running")
            return False
        if bpy.app.is_job_running("RENDER"):
            cls.poll_message_set("Blender is rendering")
            return False
        return context.scene is not None and context.scene.camera is not None

    def _fail(self, message: str):
        compare.state.last_error, compare.state.status = message, ""
        self.report({"ERROR"}, message)
        return {"CANCELLED"}

    def execute(self, context):
        """Blocking: background mode, scripts, tests."""
        try:
            job = compare.start_compare(context)
        except PreviewError as ex:
            return self._fail(str(ex))
        try:
            compare.run_reference_blocking(job)
            report = compare.finish_compare(job, job.reference.cached)
        except PreviewError as ex:
            return self._fail(str(ex))
        finally:
            job.reference.restore()
        self._done(report)
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        return self._start_modal(context)

    def _start_modal(self, context):
        try:
            self._job = compare.start_compare(context)
        except PreviewError as ex:
            return self._fail(str(ex))
        self._rendering, self._cancel_requested = False, False
        compare.state.busy, compare.state.job = True, self._job
        wm = context.window_manager
        compare.state.timer = wm.event_timer_add(POLL_INTERVAL, window=context.window)
        wm.modal_handler_add(self)
        status = self._step(context)
        return {"RUNNING_MODAL"} if "PASS_THROUGH" in status else status

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self._cancel_requested = True
            if not self._rendering:
                return self._stop(context, "Bounce GI: comparison cancelled")
            return {"PASS_THROUGH"}  # Blender's render job sees the Esc too and stops; the next poll ends ours
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        return self._step(context)

    def _step(self, context):
        """One poll: wait for the running seed, start the next, or finish once both renders are in."""
        job = self._job
        if self._rendering:
            if bpy.app.is_job_running("RENDER"):
                return self._progress(context)
            self._rendering = False
            if self._cancel_requested:
                return self._stop(context, "Bounce GI: comparison cancelled")
            if not os.path.exists(job.reference.seed_path):
                return self._stop(context, "Bounce GI: the Cycles render was cancelled or failed")
        if self._cancel_requested:
            return self._stop(context, "Bounce GI: comparison cancelled")
        try:
            if job.reference.seed_path is not None and len(job.reference.seeds) < job.reference.started_seeds:
                job.reference.end_seed()
            if job.reference.cached is None and not job.reference.done:
                return self._start_seed(context)
            if job.reference.cached is None:
                job.reference.cached = job.reference.finish()
                compare.state.status = ""
            if not job.pending.future.done():
                return self._progress(context)
            report = compare.finish_compare(job, job.reference.cached)
        except (PreviewError, OSError, RuntimeError) as ex:
            self._cleanup(context)
            return self._fail(preview.one_line(ex))
        self._cleanup(context)
        self._show_images(context)
        self._done(report)
        return {"FINISHED"}

    def _start_seed(self, context):
        compare.state.status = self._job.reference.begin_seed()
        if "CANCELLED" in bpy.ops.render.render("INVOKE_DEFAULT", write_still=True):
            self._cleanup(context)
            return self._fail("Bounce GI: Blender refused to start the Cycles render")
        self._rendering = True
        return self._progress(context)

    def _progress(self, context):
        ours = "done" if self._job.pending.future.done() else "rendering"
        cycles = compare.state.status or ("from the cache" if self._job.reference.cached else "done")
        set_status(context, f"Bounce GI compare: ours {ours}; {cycles}; {self._job.elapsed():.1f} s   Esc: cancel")
        preview.tag_redraw_all(("VIEW_3D",))
        return {"PASS_THROUGH"}

    def _stop(self, context, message: str):
        self._cleanup(context)
        compare.state.last_error = "Cancelled"
        self.report({"WARNING"}, message)
        return {"CANCELLED"}

    def cancel(self, context):
        # Blender calls this when the window closes or another file is loaded mid-comparison.
        self._cleanup(context)

    def _cleanup(self, context):
        compare.cancel(getattr(self, "_job", None))  # restores the render settings (idempotent)
        if compare.state.timer is not None:
            context.window_manager.event_timer_remove(compare.state.timer)
            compare.state.timer = None
        compare.state.busy, compare.state.job, compare.state.status = False, None, ""
        set_status(context, None)
        preview.tag_redraw_all()

    def _done(self, report: dict) -> None:
        self.report({"INFO"}, compare.summary(report))
        for text in report["warnings"][:1]:
            self.report({"WARNING"}, f"Bounce GI: {text}")

    def _show_images(self, context) -> None:
        """Show the error heat map in Image Editors that show nothing (never replace what the user picked)."""
        img = bpy.data.images.get(compare.IMAGES["error"])
        for window in context.window_manager.windows:
            for area in window.screen.areas:
                if area.type == "IMAGE_EDITOR" and area.spaces.active.image is None:
                    area.spaces.active.image = img


classes = (BOUNCE_GI_OT_compare_cycles,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.app.handlers.load_post.append(compare.forget_last_compare)


def unregister():
    # Disabling the extension mid-comparison: Blender drops the modal handler with the class; restore the render
    # settings and clear the timer here.
    compare.cancel(compare.state.job)
    if compare.state.timer is not None:
        try:
            bpy.context.window_manager.event_timer_remove(compare.state.timer)
        except (ReferenceError, AttributeError, RuntimeError):
            pass
        compare.state.timer = None
    compare.state.busy, compare.state.job = False, None
    if compare.forget_last_compare in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(compare.forget_last_compare)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
