# SPDX-License-Identifier: GPL-3.0-or-later
"""Live GI for the viewport: an edit queues one job on the engine's GPU thread, results come back progressively,
and the newest finished one is what Rendered shading (render_engine.view_draw) and the overlay (overlay.py) draw.

One LiveSession per viewport engine instance or overlay. `request(scene, settings)` (main thread, after
extraction) replaces any job not started yet, so a burst of edits costs one GI update, not one each. A job runs in
stages (STAGES): first direct light alone on a coarse atlas (a fraction of a second even on a software GL), then
the method at draft settings, then the chosen settings on the full atlas; each finished stage is uploaded
(draw.SurfaceDrawing) and drawn while the next one runs. `poll()` does the main-thread part: a bpy.app.timers
callback in Blender, called by hand in background mode and in tests. Nothing here ever waits on the GPU thread.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

from ..gpu_kernels.surface.atlas import VIEWPORT_TEXELS
from .preview import one_line

# (name, texels per atlas page, draft settings?) in the order they run; "direct" renders method "none". (The
# indirect light's atlas has fewer texels: surface/atlas.INDIRECT_SHARE.)
STAGES = (("direct", 16384, False), ("draft", 16384, True), ("final", VIEWPORT_TEXELS, False))
POLL_SECONDS = 0.02


def draft_settings(settings):
    """`settings` at the Draft quality preset of its method (addon/quality.PRESETS: coarser grid, fewer cones),
    for the draft stage; unchanged when it is already that cheap."""
    from ..addon.quality import PRESETS

    preset = PRESETS.get(settings.method, {}).get("DRAFT")
    if not preset:
        return settings
    own = getattr(settings, settings.method)
    values = {k: min(v, getattr(own, k)) for k, v in preset.items()}  # never finer than the final stage
    return replace(settings, **{settings.method: replace(own, **values)})


def stages_for(settings) -> list:
    """The (stage name, settings, texel budget) a GI update runs through for `settings`."""
    out = []
    for name, texels, draft in STAGES:
        if name == "direct":
            out.append((name, replace(settings, method="none"), texels))
        elif settings.method != "none" and draft:
            out.append((name, draft_settings(settings), texels))
        elif not draft:
            out.append((name, settings, texels))
    return out


@dataclass
class LiveStats:
    """What the panel shows about the viewport's GI."""
    stage: str = ""  # the stage on screen ("" before the first result)
    running: str = ""  # the stage computing now ("" when idle)
    timings: dict = field(default_factory=dict)  # the last finished stage's passes (s)
    skipped: list = field(default_factory=list)
    latency: dict = field(default_factory=dict)  # stage → seconds from the edit to its upload
    main_thread: dict = field(default_factory=dict)  # "extract", "upload": seconds on Blender's main thread
    texels: int = 0
    texel_size: float = 0.0
    triangles: int = 0
    warnings: list = field(default_factory=list)
    lights: dict = field(default_factory=dict)  # light type → count
    grid: str = ""  # the method's grid, e.g. "64 x 64 x 32"
    skipped_work: list = field(default_factory=list)  # what the scene let the method leave out, in words
    error: str = ""
    changed: str = ""  # what the last edit changed (changes.ChangeSet.describe)


class LiveSession:
    """The viewport's GI jobs and the drawing of the newest result (see the module docstring)."""

    def __init__(self, on_update=None, submit=None, make_drawing=None):
        self.on_update = on_update  # called on the main thread after a new result was uploaded
        self._submit = submit  # (scene, settings, texels) -> Future; default: the shared engine
        self._make_drawing = make_drawing  # SurfaceLight -> drawing; default: draw.SurfaceDrawing
        self.drawing = None  # draw.SurfaceDrawing of the newest finished stage
        self.stats = LiveStats()
        self.job = None  # (future, stage name, remaining stages, scene, edit time)
        self.queued = None  # (scene, stages, edit time): the newest request not started yet
        self.closed = False

    @property
    def busy(self) -> bool:
        return self.job is not None or self.queued is not None

    def request(self, scene, settings, edit_time: float | None = None, changed: str = "") -> None:
        """Queue a GI update of `scene` (extracted already) with `settings`, replacing one not started."""
        self.queued = (scene, stages_for(settings), time.perf_counter() if edit_time is None else edit_time)
        self.stats.changed = changed
        if self.job is None:
            self._start_queued()

    def _start_queued(self) -> None:
        scene, stages, edit_time = self.queued
        self.queued = None
        self.stats.latency = {}
        self._start(scene, stages, edit_time)

    def _start(self, scene, stages, edit_time) -> None:
        (name, settings, texels), rest = stages[0], stages[1:]
        try:
            future = self._submit_job(scene, settings, texels)
        except Exception as ex:  # bad input: one line in the panel, nothing drawn changes
            self.stats.error, self.stats.running, self.job = one_line(ex), "", None
            return
        self.job = (future, name, rest, scene, edit_time)
        self.stats.running = name

    def _submit_job(self, scene, settings, texels):
        if self._submit is not None:
            return self._submit(scene, settings, texels)
        from ..gpu_kernels.engine import get_engine

        return get_engine().submit_surface(scene, settings, texels)

    def poll(self) -> float | None:
        """Main-thread step: upload a finished stage, start the next job. Returns the delay until the next poll
        (bpy.app.timers' convention), None when there is nothing left to wait for."""
        if self.closed or self.job is None:
            return None
        future, name, rest, scene, edit_time = self.job
        if not future.done():
            return POLL_SECONDS
        self.job = None
        try:
            self._show(future.result(), name, edit_time)
        except Exception as ex:
            self.stats.error = one_line(ex)
            rest = []
        if self.queued is not None:  # a newer edit: its stages start over
            self._start_queued()
        elif rest:
            self._start(scene, rest, edit_time)
        else:
            self.stats.running = ""
        return POLL_SECONDS if self.job is not None else None

    def _show(self, light, stage: str, edit_time: float) -> None:
        start = time.perf_counter()
        if self._make_drawing is None:
            from .draw import SurfaceDrawing

            self._make_drawing = SurfaceDrawing
        drawing = self._make_drawing(light)
        old, self.drawing = self.drawing, drawing
        if old is not None:
            old.free()
        now = time.perf_counter()
        s = self.stats
        s.main_thread["upload"] = now - start
        s.latency[stage] = now - edit_time
        s.stage, s.timings, s.skipped, s.warnings, s.error = stage, dict(light.timings), list(light.skipped), \
            list(light.warnings), ""
        s.texels, s.texel_size, s.triangles = light.atlas.texel_count, light.atlas.texel, drawing.triangles
        s.lights = {k: v for k, v in light.statistics.get("lights", {}).items() if v}
        s.skipped_work = list(light.info.get("skipped_work", []))
        grid = light.info.get("grid") or light.info.get("grids")
        s.grid = " x ".join(str(n) for n in grid) if isinstance(grid, (list, tuple)) and grid and \
            all(isinstance(n, int) for n in grid) else (str(grid) if grid else "")
        if self.on_update is not None:
            self.on_update()

    def wait(self, timeout: float = 600.0) -> None:
        """Poll until every stage is drawn (background mode and tests, where no timer runs)."""
        end = time.perf_counter() + timeout
        while self.poll() is not None:
            if time.perf_counter() > end:
                raise TimeoutError(f"viewport GI did not finish within {timeout:g} s")
            time.sleep(POLL_SECONDS)

    def close(self) -> None:
        """Forget queued work, drop the drawing; a running job finishes on the GPU thread and is discarded."""
        self.closed = True
        self.queued = None
        if self.job is not None:
            self.job[0].cancel()
            self.job = None
        if self.drawing is not None:
            self.drawing.free()
            self.drawing = None
