# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's cached transfer (gpu_kernels/lpv/transfer.py) as the GPU tests read it: made by a render, the
one-bounce irradiance it gives when its clusters send a chosen flux, and what a cached edit's render is compared
by."""
import numpy as np

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv.transfer import solve
from support.stress import settings


def rendered_transfer(scene, resolution: int):
    """The Transfer a one-bounce LPV render of `scene` at `resolution`³ caches (the engine shut down after)."""
    engine = Engine()
    engine.render(scene, settings("lpv", resolution=resolution, bounces=1))
    t = engine.pipeline.cache.entries["lpv_transfer"].value[0]
    engine.shutdown()
    return t


def irradiance(t, flux) -> np.ndarray:
    """(2, R): each receiver's front and back irradiance (W/m²) when cluster c sends flux[c] W, one bounce
    (transfer.solve with no reflection)."""
    c = t.clusters.count
    grey = np.repeat(np.asarray(flux, np.float64)[:, None], 3, axis=1)
    return solve(t, np.zeros((3, c, c)), grey, 1, 0.0)[0][..., 0].astype(np.float64)


def indirect(result):
    """A render's Diffuse Indirect pass."""
    return result.passes["Diffuse Indirect"]


def rerun(result) -> list:
    """The passes a render ran (not taken from the cache)."""
    return [k for k in result.timings if k != "total" and k not in result.skipped]


def assert_same(a, b):
    """A cached edit's image against a cold render's: the same float32 arithmetic on the same data, equal to the
    rounding of sums of a few thousand terms, 1e-5 of the image's mean."""
    assert np.abs(a - b).max() <= 1e-5 * max(float(np.abs(b).mean()), 1e-12)
