# SPDX-License-Identifier: GPL-3.0-or-later
"""The GPU worker runs numpy's BLAS on one thread where its renderer is software (gl/context.share_cores): there
the renderer's "GPU" is the host's cores, which OpenBLAS's helpers kept spinning on after every product."""
import pytest

from bounce_gi.gpu_kernels.gl import host_threads
from bounce_gi.gpu_kernels.gl.context import GpuUnavailableError, GpuWorker


def test_the_worker_limits_blas_threads_on_a_software_renderer_only():
    before = host_threads.limit_blas_threads(2)
    worker = GpuWorker()
    try:
        software = worker.call(host_threads.is_software)
    except GpuUnavailableError as exc:
        pytest.skip(str(exc))
    finally:
        worker.shutdown()
        after = host_threads.limit_blas_threads(before)
    assert after == (1 if software else 2)
