# SPDX-License-Identifier: GPL-3.0-or-later
"""The process-wide render engine: one GPU worker thread, one pipeline (so caches survive between renders)."""
from __future__ import annotations

import threading
from concurrent.futures import Future

from .gl.context import GpuFailedError, GpuWorker
from .gl.preprocessor import ShaderCompileError
from .pipeline import Pipeline, RenderResult
from .scene import Scene
from .settings import RenderSettings, check_materials, check_method, check_renderable, repair_scene
from .surface.atlas import INDIRECT_SHARE, build_atlas

_engine = None
_lock = threading.Lock()


class Engine:
    def __init__(self, worker: GpuWorker | None = None):
        self.worker = worker or GpuWorker()
        self._pipeline: Pipeline | None = None

    def submit_render(self, scene: Scene, settings: RenderSettings) -> Future:
        """Queue a render on the GPU thread; the Future resolves to a RenderResult (or raises its error). Broken
        triangles and lights are left out with a warning (settings.repair_scene)."""
        scene = repair_scene(scene)
        check_renderable(scene, settings)  # fail fast, on the caller's thread, for bad input
        return self.worker.submit(self._guarded, self._render, scene, settings)

    def submit_surface(self, scene: Scene, settings: RenderSettings, budget: int,
                       indirect_budget: int | None = None) -> Future:
        """Queue the view-independent lighting of `scene` on a surface atlas of at most `budget` texels per page,
        the indirect light on one of `indirect_budget` (default budget / atlas.INDIRECT_SHARE; equal to `budget`:
        the same atlas) (pipeline.render_surface); the Future resolves to a SurfaceLight. The atlases are laid out
        on the worker thread too, so the caller (Blender's main thread) never waits for them."""
        check_method(settings)
        scene = repair_scene(scene)
        check_materials(scene)
        indirect_budget = max(1, budget // INDIRECT_SHARE) if indirect_budget is None else indirect_budget
        return self.worker.submit(self._guarded, self._render_surface, scene, settings, int(budget),
                                  int(indirect_budget))

    def submit_points(self, scene: Scene, settings: RenderSettings, positions, normals) -> Future:
        """Queue the light at N points with normals (pipeline.render_points, e.g. mesh vertices for a bake); the
        Future resolves to a PointLight."""
        check_method(settings)
        scene = repair_scene(scene)
        check_materials(scene)
        return self.worker.submit(self._guarded, lambda ctx: self._ensure_pipeline(ctx).render_points(
            scene, settings, positions, normals))

    def _guarded(self, ctx, job, *args):
        """`job(ctx, *args)`, with a failure of the GPU turned into one GpuFailedError line: a shader the driver
        rejects, or a GL error or memory exhaustion mid-render (out of memory, a lost context). After the latter
        the pipeline and the context are dropped, so the next render starts on a fresh context with nothing
        half-made in its caches."""
        import moderngl

        try:
            return job(ctx, *args)
        except ShaderCompileError as exc:
            raise GpuFailedError(f"the GPU driver could not compile a shader: {_first_line(exc)}") from exc
        except (moderngl.Error, MemoryError) as exc:
            self._drop_pipeline()
            self.worker.drop_context()
            raise GpuFailedError(f"the GPU failed during the render ({type(exc).__name__}: {_first_line(exc)}); "
                                 "lower the resolution or grid size if it ran out of memory") from exc

    def _drop_pipeline(self) -> None:
        pipeline, self._pipeline = self._pipeline, None
        if pipeline is not None:
            try:
                pipeline.release()
            except Exception:  # the objects of a failed context may not release; they go with the context
                pass

    def _ensure_pipeline(self, ctx) -> Pipeline:
        """The pipeline, made on the worker thread by its first job."""
        if self._pipeline is None:
            self._pipeline = Pipeline(ctx)
        return self._pipeline

    def render(self, scene: Scene, settings: RenderSettings) -> RenderResult:
        return self.submit_render(scene, settings).result()

    def _render(self, ctx, scene, settings):
        return self._ensure_pipeline(ctx).render(scene, settings, checked=True)  # submit_render checked them

    def _render_surface(self, ctx, scene, settings, budget, indirect_budget):
        atlas = build_atlas(scene, budget)
        coarse = None if indirect_budget == budget else build_atlas(scene, indirect_budget)
        return self._ensure_pipeline(ctx).render_surface(scene, settings, atlas, coarse)

    @property
    def pipeline(self) -> Pipeline | None:
        """The pipeline (its pass cache and programs), None before the first render. GL objects it holds belong to
        the worker thread: touch them only inside `worker.call`."""
        return self._pipeline

    def clear_cache(self) -> None:
        """Drop every cached pass result (the next render runs every pass), on the GPU thread."""
        self.worker.call(lambda ctx: self._pipeline.cache.clear() if self._pipeline else None)

    def shutdown(self) -> None:
        """Release the pipeline's GL objects and the context on the worker thread, then stop the thread (after the
        renders already queued). Safe to call twice; the engine cannot render afterwards."""
        def release(ctx):
            pipeline, self._pipeline = self._pipeline, None
            if pipeline is not None:
                pipeline.release()

        self.worker.shutdown(cleanup=release)

    def gl_info(self) -> dict:
        return self.worker.call(lambda ctx: {"renderer": ctx.info["GL_RENDERER"], "version": ctx.version_code})


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def get_engine() -> Engine:
    """The shared engine (created on first use, and again after shutdown_engine())."""
    global _engine
    with _lock:
        if _engine is None:
            _engine = Engine()
        return _engine


def shutdown_engine() -> None:
    """Shut the shared engine down, if there is one: its pipeline (pass cache, programs) and GL context are
    released on its worker thread, the thread stops, and the next get_engine() makes a fresh engine. The extension
    calls this when it is disabled, so no thread, context or cached result outlives it. Safe to call twice or before
    any engine was made; waits for a render that is running."""
    global _engine
    with _lock:
        engine, _engine = _engine, None
    if engine is not None:
        engine.shutdown()
