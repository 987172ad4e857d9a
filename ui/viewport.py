# SPDX-License-Identifier: GPL-3.0-or-later
"""What Rendered shading (render_engine.view_update / view_draw) and the overlay (overlay.py) share: turning
depsgraph updates into GI requests (ViewportFeed) and the 3D view's camera into a draw.View.

An update extracts the scene only when the GI depends on what changed (changes.ChangeSet.gi_dirty: not for a
camera or view move, a selection, a frame change without animation) or when the Bounce GI settings or the set of
visible objects changed (hiding with H sends only the Scene, like a selection click: changes.py). Orbiting
re-runs nothing; the next view_draw just draws the last result from the new view.
"""
from __future__ import annotations

import time

import bpy
import numpy as np

from . import draw
from .changes import EVERYTHING, change_set
from .live import LiveSession
from .preview import PreviewError, one_line, render_settings_of

# Extraction's resolution: the viewport has its own size, and nothing view-independent depends on this one.
EXTRACT_RESOLUTION = (64, 64)
SHADER_TICK_SECONDS = 0.05  # between compiling the display modes' shaders after a result is shown
FEEDS = []  # every open ViewportFeed (Rendered 3D views, the overlay), newest last: the panel shows the newest


def warm_up() -> None:
    """Import the extraction and the engine on a background thread, so the first switch to Rendered shading does
    not stall Blender's main thread importing (and, on a fresh install, compiling) them: ~0.1-0.2 s measured."""
    import importlib
    import threading

    def load():
        for name in ("addon.extract", "gpu_kernels.engine"):
            try:
                importlib.import_module(f"{__package__.rpartition('.')[0]}.{name}")
            except Exception:  # a missing wheel is reported when the engine is used, as one line
                return
    threading.Thread(target=load, name="bounce-gi-warm-up", daemon=True).start()


def newest_feed():
    return FEEDS[-1] if FEEDS else None


def close_all() -> None:
    """Close every feed (the extension is being disabled): no timer, job or GPU resource outlives it."""
    for feed in list(FEEDS):
        feed.close()


def region_view(region_data) -> draw.View:
    """A draw.View of a 3D view's RegionView3D (its perspective matrix = window × view)."""
    inverse = region_data.view_matrix.inverted()
    eye = tuple(inverse.translation)
    forward = -np.array(inverse.col[2][:3], np.float64)
    forward /= max(np.linalg.norm(forward), 1e-12)
    return draw.View(np.array(region_data.perspective_matrix, np.float64), eye, tuple(forward),
                     not region_data.is_perspective)


def visible_objects(depsgraph) -> frozenset:
    return frozenset(inst.object.name for inst in depsgraph.object_instances if inst.show_self)


class ViewportFeed:
    """Depsgraph updates in, LiveSession requests out (see the module docstring)."""

    def __init__(self, on_update=None):
        self.session = LiveSession(on_update=on_update)
        self.settings_key = None
        self.visible = None
        self.world_color = (0.0, 0.0, 0.0)
        self._timer_on = False
        FEEDS.append(self)

    def update(self, depsgraph, first: bool = False) -> bool:
        """Handle one depsgraph update; True when it queued a GI update."""
        start = time.perf_counter()
        changes = EVERYTHING if first or self.settings_key is None else change_set(depsgraph.updates)
        try:
            settings, _ = render_settings_of(depsgraph.scene.bounce_gi, *EXTRACT_RESOLUTION)
        except PreviewError as ex:
            self.session.stats.error = str(ex)
            return False
        visible = visible_objects(depsgraph) if changes.empty else self.visible
        if not changes.gi_dirty and settings.key() == self.settings_key and visible == self.visible:
            return False
        from ..addon.extract import ExtractError, extract_scene

        try:
            scene = extract_scene(depsgraph, EXTRACT_RESOLUTION, require_camera=False)
        except ExtractError as ex:
            self.session.stats.error = one_line(ex)
            return False
        self.settings_key, self.world_color = settings.key(), tuple(scene.world.color)
        self.visible = visible if changes.empty else visible_objects(depsgraph)
        self.session.stats.main_thread["extract"] = time.perf_counter() - start
        self.session.request(scene, settings, start, changes.describe())
        self._start_timer()
        return True

    def _start_timer(self) -> None:
        if not self._timer_on and not bpy.app.background:
            self._timer_on = True
            bpy.app.timers.register(self._tick, first_interval=0.0)

    def _tick(self):
        delay = self.session.poll()
        if delay is None and draw.compile_next_shader(self.session.drawing):
            delay = SHADER_TICK_SECONDS  # the other display modes' shaders, one a tick, while the user looks
        if delay is None:
            self._timer_on = False
        return delay

    def status(self) -> str:
        """One line for the header / panel: the stage on screen and what is still computing."""
        s = self.session.stats
        if s.error:
            return f"Bounce GI: {s.error}"
        shown = {"": "waiting for the first result", "direct": "direct light", "draft": "draft GI",
                 "final": "GI"}[s.stage]
        return f"Bounce GI: {shown}" + (f" (computing {s.running})" if s.running else "")

    def close(self) -> None:
        if self._timer_on and bpy.app.timers.is_registered(self._tick):
            bpy.app.timers.unregister(self._tick)
        self._timer_on = False
        self.session.close()
        if self in FEEDS:
            FEEDS.remove(self)
