# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.engine.shutdown_engine: what the extension's unregister() calls. After it the worker thread has
stopped, its context and cached passes are gone, and get_engine() makes a fresh engine that renders from scratch.

Uses the process-wide engine, so it shuts down whatever engine earlier tests in this process made (they get a fresh
one on their next get_engine(), which is the behaviour under test)."""
import threading

import numpy as np
import pytest

from bounce_gi.gpu_kernels import engine as engine_module
from bounce_gi.gpu_kernels.gl.context import GpuUnavailableError, GpuWorker
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.synthetic import lit_patch_scene


def gpu_threads():
    return [t for t in threading.enumerate() if t.name == "bounce-gi-gpu"]


def test_shutdown_engine_stops_the_worker_and_forgets_the_cache():
    engine_module.shutdown_engine()
    engine_module.shutdown_engine()  # twice, and with no engine: nothing to do
    scene, settings = lit_patch_scene("wall beside"), RenderSettings(method="none", width=16, height=12)

    first = engine_module.get_engine()
    try:
        a = first.render(scene, settings)
    except GpuUnavailableError as exc:
        engine_module.shutdown_engine()
        pytest.skip(str(exc))
    assert first.render(scene, settings).skipped, "the second render of the same scene should reuse the cache"
    old_thread = first.worker.thread
    assert old_thread.is_alive()

    engine_module.shutdown_engine()
    assert not old_thread.is_alive(), "the worker thread outlived shutdown_engine()"
    assert first.pipeline is None, "the pipeline (pass cache, programs) was not released"
    with pytest.raises(RuntimeError, match="shut down"):
        first.submit_render(scene, settings)
    engine_module.shutdown_engine()  # again: already shut down

    second = engine_module.get_engine()
    assert second is not first and second.worker.thread is not old_thread
    b = second.render(scene, settings)
    assert b.skipped == [], f"a fresh engine reused cached passes: {b.skipped}"
    assert np.array_equal(a.passes["Combined"], b.passes["Combined"])
    assert gpu_threads() == [second.worker.thread], gpu_threads()


def test_worker_shutdown_without_a_context_makes_none():
    made = []
    worker = GpuWorker(context_factory=lambda: made.append(1))
    worker.shutdown(cleanup=lambda ctx: made.append("cleanup"))
    worker.shutdown()
    assert not worker.thread.is_alive() and made == [], made
