# SPDX-License-Identifier: GPL-3.0-or-later
"""The one moderngl context, owned by one dedicated worker thread.

Why a thread: a moderngl context created on Blender's main thread silently breaks Blender's own drawing
(docs/conventions.md, platform facts), and GL contexts are bound to the thread that made them current. So every
GPU call in this package runs as a job on `GpuWorker`'s thread; callers get a `concurrent.futures.Future` and
results come back as numpy arrays.
"""
from __future__ import annotations

import platform
import queue
import threading
from concurrent.futures import Future

REQUIRED_GL = 430  # compute shaders and image load/store


class GpuUnavailableError(RuntimeError):
    """No OpenGL 4.3 context could be made; the message says why in one line."""


class GpuFailedError(GpuUnavailableError):
    """The GPU failed during a render: out of memory, a lost context, a shader the driver will not compile. One line
    for the user; the engine drops what it held on that context, so the next render starts afresh."""


def create_context():
    """Create a standalone OpenGL ≥ 4.3 context: EGL first (headless, works with Mesa llvmpipe), then the default."""
    import moderngl

    if platform.system() == "Darwin":
        raise GpuUnavailableError(
            "Bounce GI needs OpenGL 4.3 compute shaders; macOS stops at OpenGL 4.1, so it cannot run there")
    errors = []
    backends = ("egl", None) if platform.system() == "Linux" else (None,)
    for backend in backends:
        try:
            kwargs = {"require": REQUIRED_GL}
            if backend:
                kwargs["backend"] = backend
            return moderngl.create_standalone_context(**kwargs)
        except Exception as exc:  # moderngl raises plain Exception for version/backend problems
            errors.append(f"{backend or 'default'}: {str(exc).strip().splitlines()[0] if str(exc).strip() else exc!r}")
    raise GpuUnavailableError("could not create an OpenGL 4.3 context (" + "; ".join(errors) + ")")


def share_cores(ctx) -> None:
    """On a software renderer, numpy's BLAS on one thread: its spinning helpers would take the renderer's cores
    (host_threads.py)."""
    from .host_threads import is_software, limit_blas_threads

    if is_software(ctx):
        limit_blas_threads(1)


class GpuWorker:
    """A daemon thread that owns the GL context and runs submitted jobs in order.

    `submit(fn, *args)` runs `fn(ctx, *args)` on the worker and returns a Future. The context is created lazily by
    the first job, so constructing a worker costs nothing and a missing GPU shows up as that job's exception; a job
    after a failed creation tries again (the driver may have been fixed meanwhile).
    """

    def __init__(self, context_factory=create_context):
        self._factory = context_factory
        self._jobs: queue.Queue = queue.Queue()
        self._ctx = None
        self._closed = False
        self._submit_lock = threading.Lock()  # a job is never queued behind the shutdown sentinel
        self._thread = threading.Thread(target=self._loop, name="bounce-gi-gpu", daemon=True)
        self._thread.start()

    def submit(self, fn, *args, **kwargs) -> Future:
        """Queue `fn(ctx, *args, **kwargs)`; RuntimeError once the worker is shut down (the job would never run)."""
        future: Future = Future()
        with self._submit_lock:
            if self._closed:
                raise RuntimeError("the Bounce GI GPU worker has been shut down")
            self._jobs.put((future, fn, args, kwargs))
        return future

    def call(self, fn, *args, **kwargs):
        """Run `fn(ctx, ...)` on the worker and wait for its result (re-raises its exception)."""
        return self.submit(fn, *args, **kwargs).result()

    @property
    def thread(self) -> threading.Thread:
        return self._thread

    def _loop(self) -> None:
        while True:
            future, fn, args, kwargs = self._jobs.get()
            if fn is None:  # shutdown sentinel: args = (cleanup,)
                self._close_context(future, *args)
                return
            if not future.set_running_or_notify_cancel():
                continue
            try:
                if self._ctx is None:  # first job, or the first after drop_context: (re)try, so a cause gone is gone
                    self._ctx = self._factory()
                    share_cores(self._ctx)
                future.set_result(fn(self._ctx, *args, **kwargs))
            except BaseException as exc:
                future.set_exception(exc)

    def drop_context(self) -> None:
        """Release the context (on the worker thread, from inside a job) after the GPU failed; the next job makes a
        new one. The caller has released or forgotten every GL object made with it."""
        ctx, self._ctx = self._ctx, None
        if ctx is not None:
            try:
                ctx.release()
            except Exception:  # a lost context may fail to release too; it is gone either way
                pass

    def _close_context(self, done: Future, cleanup) -> None:
        """On the worker thread, last: `cleanup(ctx)` and the context's release, if a context was ever made."""
        ctx, self._ctx = self._ctx, None
        try:
            if ctx is not None:
                try:
                    if cleanup is not None:
                        cleanup(ctx)
                finally:
                    ctx.release()
            done.set_result(None)
        except BaseException as exc:
            done.set_exception(exc)

    def shutdown(self, cleanup=None, timeout: float | None = 30.0) -> None:
        """Stop the thread after the jobs already queued; on it, first `cleanup(ctx)` (release the GL objects made
        with the context) and then the context itself — neither runs if no job ever made a context.

        Safe to call twice. Later submits raise RuntimeError. Waits up to `timeout` seconds for the thread (a job
        that is running cannot be interrupted) and re-raises an error of the cleanup.
        """
        with self._submit_lock:
            if self._closed:
                return
            self._closed = True
            done: Future = Future()
            self._jobs.put((done, None, (cleanup,), {}))
        self._thread.join(timeout)
        if done.done():
            done.result()
