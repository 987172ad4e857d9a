# SPDX-License-Identifier: GPL-3.0-or-later
"""The steps of a preview render as plain functions, and the runtime state of the last one.

The operator (operators.py) only schedules these steps: start_render() extracts the scene and
submits it to the engine, finish_render() waits for the Future, writes the image and, when the
Output setting names a file, the render passes as a multi-layer EXR. Keeping them plain lets tests
run a whole preview in background mode, where modal operators never run. The render engine
(render_engine.py, F12 and batch) shares the middle of it: submit_scene() (extract, turn the
settings into RenderSettings with render_settings_of(), submit) and wait_result().

Engine and extraction modules are imported inside the functions, so registering the UI never
needs moderngl (a missing wheel shows up as one error line when rendering, not as a failed
register()).
"""
from __future__ import annotations

import os
import time
import traceback
from dataclasses import dataclass, field

import bpy
import numpy as np

IMAGE_NAME = "Bounce GI Preview"


class PreviewError(Exception):
    """A failure with a one-line message meant for the user (operators report it as is)."""


@dataclass
class RenderReport:
    """What the panel shows about the last finished render."""
    method: str
    width: int
    height: int
    timings: dict  # pass name -> seconds, plus "total" (the engine's own measurement)
    warnings: list
    wall_seconds: float  # submit to image written, as the user waited for it
    skipped: list = field(default_factory=list)  # passes reused from the engine's cache (time 0)
    quality: str = ""  # what the time budget chose, and why ("" when the method was chosen by hand)
    output: str = ""  # the EXR file the passes were written to ("" when the Output setting is empty)


@dataclass
class RuntimeState:
    """Module-level state, deliberately not a bpy property: it must never be saved in a .blend."""
    busy: bool = False
    last: RenderReport | None = None
    last_error: str | None = None
    timer: object | None = None  # the modal operator's window-manager timer, removed on unregister


state = RuntimeState()


@bpy.app.handlers.persistent
def forget_last_render(_dummy=None) -> None:
    """load_post handler: times and warnings of another file's render would mislead."""
    state.last = None
    state.last_error = None


@dataclass
class PendingRender:
    """A render submitted to the engine and not yet written into the image."""
    future: object  # concurrent.futures.Future resolving to a RenderResult
    method: str
    width: int
    height: int
    scene_warnings: list = field(default_factory=list)
    started: float = field(default_factory=time.perf_counter)
    quality: str = ""
    output: str = ""  # absolute path of the EXR to write the passes to, "" for none
    scene_data: object = None  # the extracted gpu_kernels.scene.Scene that was submitted

    def elapsed(self) -> float:
        return time.perf_counter() - self.started


def one_line(ex: BaseException) -> str:
    """An exception as a single line for self.report() (reports show only the first line well)."""
    text = " ".join(str(ex).split())
    return text or type(ex).__name__


def _unexpected(ex: BaseException, during: str) -> PreviewError:
    # The console gets the traceback (for bug reports); the user gets one line.
    traceback.print_exc()
    return PreviewError(f"Bounce GI {during} failed: {type(ex).__name__}: {one_line(ex)}")


def _user_facing_errors() -> tuple:
    """Engine exceptions whose message is written for the user (reported as is, no traceback)."""
    from ..gpu_kernels.gl.context import GpuUnavailableError
    from ..gpu_kernels.settings import SceneError

    return (SceneError, GpuUnavailableError)


def _not_implemented(ex: NotImplementedError, method: str) -> PreviewError:
    return PreviewError(one_line(ex) if str(ex) else f"Method {method!r} is not implemented yet")


def preview_resolution(scene, percentage: int) -> tuple[int, int]:
    """The scene's render size (after its own percentage) scaled by the preview percentage."""
    r = scene.render
    scale = r.resolution_percentage / 100.0 * percentage / 100.0
    return max(1, round(r.resolution_x * scale)), max(1, round(r.resolution_y * scale))


def start_render(scene, depsgraph) -> PendingRender:
    """Extract `scene` (must run on the main thread) at the preview size and submit it; returns without waiting.
    A bad Output path fails first, before anything renders."""
    settings = scene.bounce_gi
    output = output_file(settings.output_path)
    pending = submit_scene(depsgraph, preview_resolution(scene, settings.resolution_percentage))
    pending.output = output
    return pending


def submit_scene(depsgraph, resolution: tuple[int, int]) -> PendingRender:
    """Extract the depsgraph's scene at `resolution` (W, H) on the main thread and submit it to the engine with the
    scene's Bounce GI settings (render_settings); returns without waiting. What the preview and the render engine
    (render_engine.py) share. PreviewError, one line, for every failure: engine not importable, extraction, bad
    input, a method that is not implemented."""
    try:
        from ..addon.extract import ExtractError, extract_scene
        from ..gpu_kernels.engine import get_engine
    except ImportError as ex:
        raise PreviewError(f"Bounce GI engine unavailable: {one_line(ex)}") from None

    try:
        scene_data = extract_scene(depsgraph, resolution=resolution)
    except ExtractError as ex:
        raise PreviewError(one_line(ex)) from None
    except Exception as ex:
        raise _unexpected(ex, "scene extraction") from None
    # Extraction owns the final size (it may clamp it); render exactly what it describes.
    width, height = (int(v) for v in scene_data.resolution)
    render_settings, quality = render_settings_of(depsgraph.scene.bounce_gi, width, height)
    try:
        future = get_engine().submit_render(scene_data, render_settings)
    except NotImplementedError as ex:
        raise _not_implemented(ex, render_settings.method) from None
    except _user_facing_errors() as ex:
        raise PreviewError(one_line(ex)) from None
    except Exception as ex:
        raise _unexpected(ex, "render submission") from None
    return PendingRender(future, render_settings.method, width, height, list(scene_data.warnings), quality=quality,
                         scene_data=scene_data)


def render_settings_of(settings, width: int, height: int):
    """The engine's RenderSettings for a scene's Bounce GI settings (properties.BounceGISettings) at width × height:
    with the time budget on, what the quality table picks for it; with Auto, the table's fastest setting reaching
    the quality's error; else the chosen method at the quality's preset, with the advanced overrides. Returns
    (settings, the table choice's one-line explanation or "")."""
    from ..addon.quality import AUTO_TARGETS, QualityError, preset_settings

    if settings.use_time_budget:
        return budget_settings(settings.time_budget_ms, width, height)
    if settings.method_id() == "auto":
        return table_settings(width, height, target_error=AUTO_TARGETS[settings.quality])
    try:
        return preset_settings(settings.method_id(), settings.quality, width, height, settings.bounces,
                               settings.grid_resolution), ""
    except QualityError as ex:
        raise PreviewError(one_line(ex)) from None


def output_file(path: str) -> str:
    """The absolute EXR path the Output setting names ("" when it is empty): `//` is relative to the .blend, a
    name without extension gets `.exr`. PreviewError for a path that cannot name an EXR file."""
    path = path.strip()
    if not path:
        return ""
    if path.startswith("//") and not bpy.data.filepath:
        raise PreviewError(f"Output {path} is relative to the .blend file, which is not saved yet: save it first "
                           "or choose an absolute path")
    resolved = os.path.abspath(bpy.path.abspath(path))
    if path.endswith(("/", "\\")) or os.path.isdir(resolved):
        raise PreviewError(f"Output {path} is a folder: give a file name, e.g. "
                           f"{os.path.join(resolved, 'bounce_gi.exr')}")
    suffix = os.path.splitext(resolved)[1]
    if not suffix:
        return resolved + ".exr"
    if suffix.lower() != ".exr":
        raise PreviewError(f"Output {path} must be an .exr file (the passes are written as a multi-layer EXR)")
    return resolved


def write_output(path: str, passes: dict) -> None:
    """Write the render passes as a multi-layer EXR, creating its folder as Blender does for render output."""
    from ..gpu_kernels.output.exr import write_passes

    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        write_passes(path, passes)
    except ImportError as ex:
        raise PreviewError(f"Bounce GI could not write {path}: EXR support unavailable ({one_line(ex)})") from None
    except OSError as ex:  # strerror, where there is one: the temporary file's name would only confuse
        raise PreviewError(f"Bounce GI could not write {path}: {ex.strerror or one_line(ex)}") from None
    except Exception as ex:
        raise _unexpected(ex, f"writing {path}") from None


def budget_settings(budget_ms: float, width: int, height: int):
    """RenderSettings for a time budget from the measured quality table; (settings, one-line explanation)."""
    return table_settings(width, height, budget_ms=budget_ms)


def table_settings(width: int, height: int, budget_ms=None, target_error=None):
    """RenderSettings the measured quality table picks for a budget and/or an error target; (settings, why)."""
    from ..addon.quality import QualityError, choose, load_table, render_settings_for

    try:
        table = load_table()
        choice = choose(table, budget_ms=budget_ms, target_error=target_error)
    except QualityError as ex:
        raise PreviewError(one_line(ex)) from None
    return render_settings_for(choice, width, height), choice.describe(table)


def wait_result(pending: PendingRender, timeout: float | None = None):
    """The RenderResult of a submitted render, waiting up to `timeout` seconds (None: as long as it takes);
    PreviewError, one line, when it failed, was cancelled or did not finish in time."""
    import concurrent.futures

    try:
        return pending.future.result(timeout=timeout)
    except NotImplementedError as ex:
        raise _not_implemented(ex, pending.method) from None
    except _user_facing_errors() as ex:
        raise PreviewError(one_line(ex)) from None
    except concurrent.futures.CancelledError:
        raise PreviewError("Bounce GI render was cancelled") from None
    except concurrent.futures.TimeoutError:
        raise PreviewError(f"Bounce GI render did not finish within {timeout:g} s") from None
    except Exception as ex:
        raise _unexpected(ex, "render") from None


def finish_render(pending: PendingRender, timeout: float | None = None) -> RenderReport:
    """Wait for the engine, write the Combined pass into the preview image, record the report, write the passes
    to the Output file if one is set."""
    result = wait_result(pending, timeout)
    if "Combined" not in result.passes:
        raise PreviewError(f"Bounce GI engine returned no Combined pass (got {sorted(result.passes)})")
    write_preview_image(result.passes["Combined"])
    # Scene warnings first (they explain the render), then the engine's; drop repeats, keep order.
    warnings = list(dict.fromkeys([*pending.scene_warnings, *result.warnings]))
    report = RenderReport(pending.method, pending.width, pending.height, dict(result.timings), warnings,
                          pending.elapsed(), list(getattr(result, "skipped", [])), pending.quality)
    state.last, state.last_error = report, None
    if pending.output:
        # After the preview is shown and recorded: a failed write is reported, the image and times stay.
        write_output(pending.output, result.passes)
        report.output = pending.output
    return report


def write_preview_image(combined: np.ndarray, name: str = IMAGE_NAME):
    """Copy an (H, W, 3|4) float array, rows top-to-bottom, into a float Image datablock.

    The datablock is reused (resized when needed) rather than replaced, so an Image Editor that
    shows it keeps showing it. Float buffers hold scene-linear values, which is what the engine
    produces; no view transform is baked in.
    """
    a = np.asarray(combined, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] not in (3, 4) or a.shape[0] < 1 or a.shape[1] < 1:
        raise PreviewError(f"Bounce GI Combined pass has shape {a.shape}, expected (H, W, 3 or 4)")
    h, w = a.shape[:2]
    if a.shape[2] == 3:
        a = np.concatenate([a, np.ones((h, w, 1), np.float32)], axis=2)
    # Blender stores pixels bottom row first; the engine gives rows top to bottom.
    rgba = np.ascontiguousarray(a[::-1])

    img = bpy.data.images.get(name)
    if img is not None and (img.source != "GENERATED" or not img.is_float):
        # A file, or a byte image (sRGB colour space) with our name: keep it, under another name.
        img.name = name + " (old)"
        img = None
    if img is None:
        # A new float buffer gets the scene-linear colour space.
        img = bpy.data.images.new(name, width=w, height=h, alpha=True, float_buffer=True)
    elif tuple(img.size) != (w, h):
        # Changing the generated size re-creates the pixel buffer in place (keeps editors' references).
        img.generated_width, img.generated_height = w, h
    img.pixels.foreach_set(rgba.ravel())
    img.update()
    return img


def tag_redraw_all(area_types=("VIEW_3D", "IMAGE_EDITOR")) -> None:
    """Redraw the sidebar (times, warnings) and any Image Editor showing the preview."""
    wm = bpy.context.window_manager
    for window in getattr(wm, "windows", ()):
        for area in window.screen.areas:
            if area.type in area_types:
                area.tag_redraw()
