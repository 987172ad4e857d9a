# SPDX-License-Identifier: GPL-3.0-or-later
"""The GPU tests' shared fixtures: a bare OpenGL 4.3 context (Mesa llvmpipe through EGL where there is no GPU), the
same with a shader program cache, and two engines (a warm one that is edited, a cold one to compare it with), one
per test module."""
import pytest

from bounce_gi.gpu_kernels.gl.programs import ProgramCache


@pytest.fixture(scope="module")
def gl_context():
    moderngl = pytest.importorskip("moderngl")
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception as exc:  # no EGL / GL 4.3 on this machine
        pytest.skip(f"no OpenGL 4.3 context: {exc}")
    yield ctx
    ctx.release()


@pytest.fixture(scope="module")
def gl(gl_context):
    """(context, ProgramCache)."""
    programs = ProgramCache(gl_context)
    yield gl_context, programs
    programs.release()


@pytest.fixture(scope="module")
def engines():
    """(warm, cold): two Engines, for an edit applied to the first and rendered afresh by the second."""
    from bounce_gi.gpu_kernels.engine import Engine
    from bounce_gi.gpu_kernels.gl.context import GpuUnavailableError

    warm, cold = Engine(), Engine()
    try:
        warm.gl_info()
    except GpuUnavailableError as exc:
        warm.shutdown()
        cold.shutdown()
        pytest.skip(str(exc))
    yield warm, cold
    warm.shutdown()
    cold.shutdown()
