# SPDX-License-Identifier: GPL-3.0-or-later
"""lpv/regional.py's choice of the voxels an object's move voxelises again (the GPU side: tests/gpu/
test_voxelize_region.py)."""
import numpy as np

from bounce_gi.gpu_kernels.lpv.regional import like_the_grid


def _pot(n):
    return n & (n - 1) == 0


def test_a_region_grows_to_the_grids_power_of_two_pattern_and_stays_inside_it():
    """Random regions of random grids: the grown region holds the region, lies in the grid, and each of its sizes
    is a power of two exactly where the grid's is (llvmpipe's shader variants, regional.like_the_grid), grown by
    no more than it must: one voxel past a power of two, or up to the next power of two."""
    rng = np.random.default_rng(5)
    for _ in range(2000):
        size = rng.integers(1, 80, 3)
        if rng.random() < 0.3:
            size[rng.integers(3)] = 2 ** rng.integers(0, 7)
        lo = np.array([rng.integers(0, n) for n in size])
        hi = np.array([rng.integers(a + 1, n + 1) for a, n in zip(lo, size)])
        glo, ghi = like_the_grid(lo, hi, size)
        assert np.all(glo <= lo) and np.all(ghi >= hi) and np.all(glo >= 0) and np.all(ghi <= size)
        for a in range(3):
            e, g = int(hi[a] - lo[a]), int(ghi[a] - glo[a])
            assert _pot(g) == _pot(int(size[a]))
            assert g == e or (_pot(int(size[a])) and g < 2 * e) or (not _pot(int(size[a])) and g <= e + 2)
