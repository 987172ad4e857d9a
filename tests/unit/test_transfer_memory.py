# SPDX-License-Identifier: GPL-3.0-or-later
"""Where an updated transfer's T is written (gpu_kernels/lpv/transfer.empty_matrix, gl/pass_cache.PassCache.spare):
into the memory of the T the cache would release, where it fits, else into new memory with room to grow."""
import numpy as np

from bounce_gi.gpu_kernels.gl.pass_cache import PassCache
from bounce_gi.gpu_kernels.lpv.transfer import empty_matrix


def test_new_memory_leaves_an_eighth_to_grow_into():
    a = empty_matrix((2, 100, 80))
    assert a.shape == (2, 100, 80) and a.dtype == np.float32 and a.flags.c_contiguous
    assert a.base.size == 16000 + 16000 // 8
    grown = empty_matrix((2, 104, 84), spare=a)  # 17472 ≤ 18000: a few clusters and receivers more fit
    assert grown.shape == (2, 104, 84) and np.shares_memory(grown, a)


def test_the_room_to_grow_stays_within_the_budget():
    """`most` (the transfer_mb budget, in elements) caps the buffer: the eighth is cut to what the budget leaves, and
    none where T alone fills it."""
    assert empty_matrix((2, 100, 80), most=16500).base.size == 16500
    assert empty_matrix((2, 100, 80), most=16000).base.size == 16000
    assert empty_matrix((2, 100, 80), most=10**9).base.size == 18000


def test_a_spare_is_reused_only_where_it_fits_and_is_not_much_larger():
    spare = empty_matrix((2, 100, 80))  # 18000 floats of memory
    assert not np.shares_memory(empty_matrix((2, 120, 80), spare=spare), spare)  # 19200: too small
    assert not np.shares_memory(empty_matrix((2, 50, 80), spare=spare), spare)  # 8000: would keep 2.25× its size
    assert np.shares_memory(empty_matrix((2, 90, 80), spare=spare), spare)  # 14400 ≤ 18000 ≤ 1.25 × 14400
    assert not np.shares_memory(empty_matrix((2, 90, 80), spare=np.zeros(18000, np.float64)), spare)
    read_only = np.frombuffer(np.zeros(18000, np.float32).tobytes(), np.float32)  # as a read-back gives it
    assert not np.shares_memory(empty_matrix((2, 90, 80), spare=read_only), read_only)
    assert empty_matrix((0, 5, 5), spare=None).shape == (0, 5, 5)


class Held:
    def __init__(self):
        self.released = 0

    def release(self):
        self.released += 1


def test_the_cache_hands_over_the_output_it_would_release():
    """keep = 2: with two outputs kept, storing a third releases the older one: spare() hands that one over
    instead (and the cache no longer holds it); none while fewer are kept, none with one kept (the newest is the
    prior an update reads), none where it is the prior the caller names."""
    cache = PassCache(keep={"t": 2})
    a, b, c = Held(), Held(), Held()
    assert cache.spare("t") is None
    cache.run("t", ("A",), lambda: a)
    assert cache.spare("t") is None  # one kept: nothing would go
    cache.run("t", ("B",), lambda: b)
    assert cache.spare("t", besides=a) is None and [k for k, _ in cache.kept("t")] == [("B",), ("A",)]
    assert cache.spare("t") is a and [k for k, _ in cache.kept("t")] == [("B",)]
    cache.run("t", ("C",), lambda: c)
    assert a.released == 0 and b.released == 0  # handed over, not released; B kept beside C
    single = PassCache()
    single.run("u", ("A",), lambda: Held())
    assert single.spare("u") is None
