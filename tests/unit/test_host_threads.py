# SPDX-License-Identifier: GPL-3.0-or-later
"""gl/host_threads.py: numpy's OpenBLAS found and set to a thread count, and which renderers count as software."""
from types import SimpleNamespace

import numpy as np

from bounce_gi.gpu_kernels.gl import host_threads


def test_limit_blas_threads_sets_the_count_numpy_uses_and_returns_the_one_before():
    before = host_threads.blas_threads()
    # numpy's wheels for the platforms we ship (Linux and Windows x86-64) bundle OpenBLAS: found, or the limit is
    # silently a no-op and the renderer's cores go on being shared with its spinning helpers.
    assert before is not None and before >= 1
    try:
        assert host_threads.limit_blas_threads(2) == before
        assert host_threads.blas_threads() == 2
        assert host_threads.limit_blas_threads(1) == 2
        assert host_threads.blas_threads() == 1
        a = np.arange(64.0).reshape(8, 8)
        assert np.allclose(a @ np.eye(8), a)  # products still run
    finally:
        host_threads.limit_blas_threads(before)
    assert host_threads.blas_threads() == before


def test_software_renderers_are_told_from_hardware_ones():
    def ctx(renderer):
        return SimpleNamespace(info={"GL_RENDERER": renderer})

    assert host_threads.is_software(ctx("llvmpipe (LLVM 15.0.6, 256 bits)"))
    assert host_threads.is_software(ctx("softpipe"))
    assert not host_threads.is_software(ctx("NVIDIA H100 80GB HBM3/PCIe/SSE2"))
    assert not host_threads.is_software(ctx("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 17.0.6, DRM 3.54)"))
    assert not host_threads.is_software(SimpleNamespace(info={}))


def test_beside_runs_on_another_thread_and_hands_back_its_result_or_error():
    import threading

    import pytest

    from bounce_gi.gpu_kernels.gl.host_threads import beside
    assert beside(lambda a, b: (a + b, threading.get_ident()), 2, 3).result()[0] == 5
    assert beside(threading.get_ident).result() != threading.get_ident()

    def fails():
        raise ValueError("from the other thread")
    with pytest.raises(ValueError, match="other thread"):
        beside(fails).result()
