# SPDX-License-Identifier: GPL-3.0-or-later
"""The process-wide render engine: one GPU worker thread, one pipeline (so caches survive between renders)."""
from __future__ import annotations

import threading
from concurrent.futures import Future

from .gl.context import GpuWorker
from .pipeline import Pipeline, RenderResult
from .scene import Scene
from .settings import RenderSettings, check_renderable

_engine = None
_lock = threading.Lock()


class Engine:
    def __init__(self, worker: GpuWorker | None = None):
        self.worker = worker or GpuWorker()
        self._pipeline: Pipeline | None = None

    def submit_render(self, scene: Scene, settings: RenderSettings) -> Future:
        """Queue a render on the GPU thread; the Future resolves to a RenderResult (or raises its error)."""
        check_renderable(scene, settings)  # fail fast, on the caller's thread, for bad input
        return self.worker.submit(self._render, scene, settings)

    def render(self, scene: Scene, settings: RenderSettings) -> RenderResult:
        return self.submit_render(scene, settings).result()

    def _render(self, ctx, scene, settings):
        if self._pipeline is None:
            self._pipeline = Pipeline(ctx)
        return self._pipeline.render(scene, settings)

    @property
    def pipeline(self) -> Pipeline | None:
        """The pipeline (its pass cache and programs), None before the first render. GL objects it holds belong to
        the worker thread: touch them only inside `worker.call`."""
        return self._pipeline

    def clear_cache(self) -> None:
        """Drop every cached pass result (the next render runs every pass), on the GPU thread."""
        self.worker.call(lambda ctx: self._pipeline.cache.clear() if self._pipeline else None)

    def gl_info(self) -> dict:
        return self.worker.call(lambda ctx: {"renderer": ctx.info["GL_RENDERER"], "version": ctx.version_code})


def get_engine() -> Engine:
    """The shared engine (created on first use)."""
    global _engine
    with _lock:
        if _engine is None:
            _engine = Engine()
        return _engine
