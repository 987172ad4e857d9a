# SPDX-License-Identifier: GPL-3.0-or-later
"""The GPU failing, forced: no OpenGL 4.3 (a failed context creation), a shader the driver will not compile, the
GPU running out of memory or being lost in the middle of a render. Each is one clear line (GpuUnavailableError or
its GpuFailedError), and the next render works once the cause is gone (the CLI's side: test_cli_failures.py)."""
import moderngl
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.gl.context import GpuFailedError, GpuUnavailableError, GpuWorker, create_context
from support.stress import box_room, check_sane, settings


@pytest.fixture(scope="module")
def own_engine():
    """An engine of this module's own: its contexts are dropped on purpose."""
    engine = Engine()
    yield engine
    engine.shutdown()


def one_line(exc) -> str:
    text = str(exc)
    assert text and "\n" not in text and "Traceback" not in text, text
    return text


def render_ok(engine, method="vct", scale=1.0):
    scene, s = box_room(scale), settings(method)
    result = engine.render(scene, s)
    check_sane(result, scene, s)
    return result


def test_no_opengl_43_is_one_line_and_the_next_attempt_works():
    attempts = []

    def factory():
        attempts.append(1)
        if len(attempts) == 1:  # what create_context raises where the driver stops at OpenGL 4.1
            raise GpuUnavailableError("could not create an OpenGL 4.3 context (egl: requested 430, got 410)")
        return create_context()

    engine = Engine(GpuWorker(context_factory=factory))
    try:
        with pytest.raises(GpuUnavailableError) as err:
            engine.render(box_room(), settings("none"))
        assert "OpenGL 4.3" in one_line(err.value)
        render_ok(engine, "none")  # the driver is back: the worker tries again instead of repeating the error
        assert len(attempts) == 2
    finally:
        engine.shutdown()


def test_a_factory_that_raises_anything_is_retried():
    calls = []

    def factory():
        calls.append(1)
        raise RuntimeError("eglInitialize failed")

    worker = GpuWorker(context_factory=factory)
    try:
        for _ in range(2):
            with pytest.raises(RuntimeError, match="eglInitialize failed"):
                worker.call(lambda ctx: None)
        assert len(calls) == 2
    finally:
        worker.shutdown()


@pytest.mark.parametrize("stage", ("program", "compute_shader"))
def test_a_shader_the_driver_rejects_is_one_line(monkeypatch, stage):
    """An unusual driver refuses a program (raster or compute): one line naming it; the next render compiles."""
    def refuse(self, *args, **kwargs):
        raise moderngl.Error("0:12(3): error: syntax error, unexpected IDENTIFIER\n0:12(3): error: more")

    engine = Engine()
    try:
        monkeypatch.setattr(moderngl.Context, stage, refuse)
        with pytest.raises(GpuFailedError) as err:
            engine.render(box_room(), settings("vct"))
        assert "could not compile a shader" in one_line(err.value)
        monkeypatch.undo()
        render_ok(engine)
    finally:
        engine.shutdown()


FAILURES = {"out of memory": (moderngl.Context, "texture3d", "GL_OUT_OF_MEMORY"),
            "lost context": (moderngl.ComputeShader, "run", "GL_CONTEXT_LOST: the GPU was reset"),
            "buffer out of memory": (moderngl.Context, "buffer", "GL_OUT_OF_MEMORY")}


@pytest.mark.parametrize("failure", FAILURES)
@pytest.mark.parametrize("method", ("lpv", "vct"))
def test_the_gpu_failing_mid_render_is_one_line_and_the_next_render_is_whole(own_engine, monkeypatch, failure,
                                                                            method):
    cls, name, message = FAILURES[failure]
    reference = render_ok(own_engine, method).passes["Combined"]
    calls = []
    original = getattr(cls, name)

    def fail_later(self, *args, **kwargs):  # the failure comes mid-render, after some GL work went through
        calls.append(1)
        if len(calls) == 3:
            raise moderngl.Error(message)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(cls, name, fail_later)
    with pytest.raises(GpuFailedError) as err:
        render_ok(own_engine, method, scale=1.5)  # a new scene: its passes run (and allocate)
    assert message.split(":")[0] in one_line(err.value)
    monkeypatch.undo()
    # The context and every cached pass went with the failure; the same frame renders again from scratch, equal to
    # a render that never failed.
    assert own_engine.pipeline is None
    np.testing.assert_array_equal(render_ok(own_engine, method).passes["Combined"], reference)
