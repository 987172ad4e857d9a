# SPDX-License-Identifier: GPL-3.0-or-later
"""The Bounce GI render engine (`bl_idname` BOUNCE_GI): F12, `blender -b FILE -E BOUNCE_GI -f N | -a`, and so any
farm manager that runs exactly that.

`render(depsgraph)` extracts the frame's scene at Blender's render size (resolution × percentage), submits it with
the scene's Bounce GI settings (the same steps as the preview: preview.submit_scene), waits for the engine in short
polls that honour Esc (`test_break`), then writes every pass of gpu_kernels.compose into the render result under its
Cycles name, and prints one log line a frame: its time and the passes the engine's cache reused (an animation,
`-a`, renders every frame through the one process-wide engine, so a frame where only a light moved reuses the
geometry and G-buffer of the frame before). The result is begun only once every pass is in hand, so a failure
never leaves a half-written one: it is one ERROR report and an empty result. With Render Region (`use_border`) the
full frame is rendered and the region copied out (Blender then crops or places it, as for any engine). One render
per view layer, mono only.

Rendered shading: `view_update` hands the depsgraph's updates to a viewport.ViewportFeed (extract what the GI
depends on, queue one job on the GPU thread, never wait); `view_draw` draws the newest finished result from the
3D view's camera with draw.SurfaceDrawing straight into the 3D view's scene-linear framebuffer (Blender applies
the view transform, as for any engine's image: draw.draw_view3d). Orbiting redraws; it re-runs no GI pass.
Material Preview shading uses EEVEE (`bl_use_eevee_viewport`).
"""
import concurrent.futures
import traceback

import bpy
import numpy as np

from . import preview
from .preview import PreviewError

ENGINE_ID = "BOUNCE_GI"
# How often render() checks the Future and Esc: short enough that cancelling feels immediate.
POLL_INTERVAL = 0.05

# The passes as Cycles registers them: (name, channels, channel letters, type). Every one is always written (the
# pipeline computes them all anyway), whatever the view layer's pass toggles say.
PASSES = (
    ("Combined", 4, "RGBA", "COLOR"),
    ("Diffuse Direct", 3, "RGB", "COLOR"),
    ("Diffuse Indirect", 3, "RGB", "COLOR"),
    ("Diffuse Color", 3, "RGB", "COLOR"),
    ("Glossy Direct", 3, "RGB", "COLOR"),
    ("Glossy Indirect", 3, "RGB", "COLOR"),
    ("Glossy Color", 3, "RGB", "COLOR"),
    ("Emission", 3, "RGB", "COLOR"),
    ("AO", 3, "RGB", "COLOR"),
    ("Normal", 3, "XYZ", "VECTOR"),
    ("Position", 3, "XYZ", "VECTOR"),
    ("Depth", 1, "Z", "VALUE"),  # Blender's own Z pass
)


def region(render, width: int, height: int) -> tuple[int, int, int, int]:
    """The pixels Blender's render result holds, as (x, y, w, h) in the full width × height frame, y counted from
    the bottom: the whole frame, or the Render Region computed as Blender does (float border × size, truncated)."""
    if not render.use_border:
        return 0, 0, width, height
    f = np.float32  # Blender multiplies its float border by the int size in single precision
    x0, x1 = int(f(render.border_min_x) * f(width)), int(f(render.border_max_x) * f(width))
    y0, y1 = int(f(render.border_min_y) * f(height)), int(f(render.border_max_y) * f(height))
    return x0, y0, x1 - x0, y1 - y0


def result_pixels(image: np.ndarray, rect: tuple[int, int, int, int]) -> np.ndarray:
    """An (H, W, C) pass, rows top-to-bottom, as a RenderPass.rect wants it: the region's pixels, rows bottom-up,
    as (w·h, C) float32."""
    x, y, w, h = rect
    a = np.asarray(image, np.float32)
    if a.ndim == 2:
        a = a[..., None]
    bottom_up = a[::-1]
    return np.ascontiguousarray(bottom_up[y:y + h, x:x + w]).reshape(w * h, a.shape[2])


def frame_log_line(frame: int, pending, result) -> str:
    """`Bounce GI: frame 2: LPV 64 x 48 in 812 ms (wall 0.85 s); reused geometry, textures, gbuffer`."""
    total = result.timings.get("total", pending.elapsed())
    reused = ", ".join(result.skipped) or "nothing"
    return (f"Bounce GI: frame {frame}: {pending.method.upper()} {pending.width} x {pending.height} in "
            f"{total * 1000:.0f} ms (wall {pending.elapsed():.2f} s); reused {reused}")


class BounceGIRenderEngine(bpy.types.RenderEngine):
    """F12 and batch rendering with Bounce GI (see the module docstring)."""

    bl_idname = ENGINE_ID
    bl_label = "Bounce GI"
    bl_use_preview = False  # material and light thumbnails stay with EEVEE
    bl_use_shading_nodes_custom = False  # Blender's shader nodes: extraction reads Principled, Diffuse, Emission
    bl_use_eevee_viewport = True  # Material Preview shading with EEVEE; Rendered shading is ours

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)  # Blender passes the engine's RNA pointer
        self.feed = None  # viewport.ViewportFeed, made by the first view_update

    def __del__(self):
        try:
            self.free_viewport()
        except (ReferenceError, AttributeError):  # Blender already freed the RNA struct
            pass

    def free_viewport(self) -> None:
        if getattr(self, "feed", None) is not None:
            self.feed.close()
            self.feed = None

    def view_update(self, context, depsgraph):
        from .viewport import ViewportFeed

        first = self.feed is None or self.feed.session.closed  # closed: another file was loaded
        if first:
            self.feed = ViewportFeed(on_update=self.tag_redraw)
        self.feed.update(depsgraph, first=first)

    def view_draw(self, context, depsgraph):
        from . import draw
        from .viewport import region_view

        feed = self.feed
        drawing = feed.session.drawing if feed is not None else None
        background = feed.world_color if feed is not None else (0.0, 0.0, 0.0)
        mode = depsgraph.scene.bounce_gi.display_mode
        draw.draw_view3d(drawing, region_view(context.region_data), background, mode)
        if feed is not None:
            self.update_stats("", feed.status())

    def update_render_passes(self, scene=None, renderlayer=None):
        for name, channels, letters, kind in PASSES:
            self.register_pass(scene, renderlayer, name, channels, letters, kind)

    def render(self, depsgraph):
        width, height = self.resolution_x, self.resolution_y  # Blender's render size, percentage applied
        try:
            pending = preview.submit_scene(depsgraph, (width, height))
            if not self._wait(pending):
                return  # Esc: no result is begun, the render ends empty
            result = preview.wait_result(pending)
            if (pending.width, pending.height) != (width, height):
                raise PreviewError(f"Bounce GI rendered {pending.width}x{pending.height}, Blender expects "
                                   f"{width}x{height}")
            self._write(depsgraph, result.passes, region(depsgraph.scene.render, width, height))
        except PreviewError as ex:
            self.report({"ERROR"}, str(ex))
            return
        except Exception as ex:  # a bug: the console gets the traceback, the user one line
            traceback.print_exc()
            self.report({"ERROR"}, f"Bounce GI render failed: {type(ex).__name__}: {preview.one_line(ex)}")
            return
        self._report_done(pending, result, depsgraph.scene.frame_current)

    def _wait(self, pending) -> bool:
        """Wait for the engine, polling so Esc works; False when the user cancelled. A render already running on
        the GPU cannot be interrupted: cancelling stops the wait, and the engine drops the result."""
        self.update_progress(0.0)
        while not concurrent.futures.wait([pending.future], timeout=POLL_INTERVAL).done:
            if self.test_break():
                pending.future.cancel()
                return False
            self.update_stats("Bounce GI", f"{pending.method.upper()} {pending.width} x {pending.height}, "
                                           f"{pending.elapsed():.1f} s")
        return True

    def _write(self, depsgraph, passes: dict, rect) -> None:
        missing = [name for name, *_ in PASSES if name not in passes]
        if missing:
            raise PreviewError(f"Bounce GI engine returned no {', '.join(missing)} pass")
        x, y, w, h = rect
        result = self.begin_result(0, 0, w, h, layer=depsgraph.view_layer.name)
        if (result.resolution_x, result.resolution_y) != (w, h) or not result.layers:
            self.end_result(result, cancel=True)
            raise PreviewError(f"Blender's render result is {result.resolution_x}x{result.resolution_y}, "
                               f"the render region {w}x{h}")
        try:
            layer = result.layers[0]
            for name, *_ in PASSES:
                target = layer.passes.get(name)
                if target is not None:  # every registered pass is there; Blender decides, not us
                    target.rect = result_pixels(passes[name], rect)
        except BaseException:
            self.end_result(result, cancel=True)  # never a half-written result
            raise
        self.end_result(result)

    def _report_done(self, pending, result, frame: int) -> None:
        self.update_progress(1.0)
        total = result.timings.get("total", pending.elapsed())
        self.update_stats("Bounce GI", f"{pending.method.upper()} {pending.width} x {pending.height} in "
                                       f"{total * 1000:.0f} ms")
        # The render log (stdout, beside Blender's own "Fra:" lines): one line a frame, with what the engine's pass
        # cache reused from the frame before (an animation renders through the one process-wide engine).
        print(frame_log_line(frame, pending, result), flush=True)
        warnings = list(dict.fromkeys([*pending.scene_warnings, *result.warnings]))
        if warnings:
            more = f" (+{len(warnings) - 1} more)" if len(warnings) > 1 else ""
            self.report({"WARNING"}, f"Bounce GI: {warnings[0]}{more}")


# Blender's own panels (camera, light, output, colour management, ...) show only for the engines they list. As
# Blender's render engine template does, list ours in those that hold for any engine ('BLENDER_RENDER'), except the
# view layer's pass toggles (every pass is always written), plus the material and world surface panels: extraction
# reads those node trees.
EXTRA_PANELS = ("EEVEE_MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface")
SKIPPED_PANELS = ("VIEWLAYER_PT_filter", "VIEWLAYER_PT_layer_passes")


def builtin_panels() -> list:
    """Blender's panels that should show with Bounce GI as the render engine."""
    return [p for p in bpy.types.Panel.__subclasses__() if isinstance(getattr(p, "COMPAT_ENGINES", None), set)
            and p.__name__ not in SKIPPED_PANELS
            and ("BLENDER_RENDER" in p.COMPAT_ENGINES or p.__name__ in EXTRA_PANELS)]


classes = (BounceGIRenderEngine,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    for panel in builtin_panels():
        panel.COMPAT_ENGINES.add(ENGINE_ID)


def unregister():
    for panel in builtin_panels():
        panel.COMPAT_ENGINES.discard(ENGINE_ID)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
