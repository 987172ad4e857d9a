# SPDX-License-Identifier: GPL-3.0-or-later
"""The host's BLAS threads while a software renderer shares its cores.

numpy's OpenBLAS runs a matrix product on every core, and its helper threads then keep spinning, waiting for the next
product, for a while after it returned. On a software renderer (Mesa llvmpipe) the "GPU" is those same cores: a
helper spinning after the LPV's bounce solve (a product with its transfer) took a core from the passes after it — an
area light's RSM records in the Cornell box took 27–31 ms instead of 16 (benchmarks/results/llvmpipe/incremental.md,
stop 48). So where the renderer is software the engine runs BLAS on one thread (`limit_blas_threads`). It is
process-wide: numpy offers no per-call setting. Found as threadpoolctl finds it, without the dependency: the
OpenBLAS library numpy loaded, by the names its builds give its thread-count functions.

With BLAS on one thread, two independent products can still use two cores: `beside` runs one on a second host
thread (numpy releases the GIL in a product) while the caller computes the other."""
from __future__ import annotations

import ctypes
import functools
import glob
import os
import sys
from concurrent.futures import Future, ThreadPoolExecutor

SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "swiftshader", "lavapipe")
# (set, get) per OpenBLAS build: numpy ≥ 2's scipy-openblas, numpy 1.x's 64-bit-integer build, a plain one.
_FUNCTIONS = (("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
              ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
              ("openblas_set_num_threads", "openblas_get_num_threads"))


@functools.cache
def _second_thread() -> ThreadPoolExecutor:
    """The one worker thread `beside` runs on, made at its first use."""
    return ThreadPoolExecutor(1, thread_name_prefix="bounce-gi-beside")


def beside(fn, *args) -> Future:
    """fn(*args) run on a second host thread while the caller goes on; its Future (.result() waits for it and
    raises what it raised)."""
    return _second_thread().submit(fn, *args)


def is_software(ctx) -> bool:
    """Whether the context renders on the CPU (its GL_RENDERER names a software rasteriser)."""
    renderer = str(ctx.info.get("GL_RENDERER", "")).lower()
    return any(name in renderer for name in SOFTWARE_RENDERERS)


def _library_paths() -> list:
    """Paths of the OpenBLAS libraries numpy may have loaded: its wheel's numpy.libs folder, and (Linux) any
    OpenBLAS mapped into the process."""
    import numpy

    libs = os.path.join(os.path.dirname(os.path.dirname(numpy.__file__)), "numpy.libs")
    paths = sorted(glob.glob(os.path.join(libs, "*openblas*")))
    if sys.platform.startswith("linux"):
        try:
            with open("/proc/self/maps", encoding="utf-8", errors="replace") as maps:
                paths += sorted({line.split()[-1] for line in maps if "openblas" in line.lower() and "/" in line})
        except OSError:
            pass
    return list(dict.fromkeys(paths))


def _thread_functions() -> list:
    """(set, get) ctypes functions of each OpenBLAS found (opening a loaded library returns that library)."""
    found = []
    for path in _library_paths():
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for set_name, get_name in _FUNCTIONS:
            if hasattr(lib, set_name) and hasattr(lib, get_name):
                found.append((getattr(lib, set_name), getattr(lib, get_name)))
                break
    return found


def blas_threads() -> int | None:
    """The thread count of the first OpenBLAS found, None where there is none."""
    functions = _thread_functions()
    return int(functions[0][1]()) if functions else None


def limit_blas_threads(count: int) -> int | None:
    """Run every OpenBLAS found on `count` threads; returns the count it had before, None where none was found
    (another BLAS, or none: nothing to do)."""
    functions = _thread_functions()
    if not functions:
        return None
    before = int(functions[0][1]())
    for set_threads, _ in functions:
        set_threads(ctypes.c_int(int(count)))
    return before
