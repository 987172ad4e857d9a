# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.output.metrics: rel-L1 and relMSE as docs/conventions.md defines them, masks, and the heat-map ramp."""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.output import metrics

# Two pixels, RGB. |x − r| = (1, 0, 0 | 0, 0, 3); Σ|r| = 21.
REF = np.array([[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]])
X = np.array([[[2.0, 2.0, 3.0], [4.0, 5.0, 3.0]]])


def test_rel_l1_hand_computed():
    assert metrics.rel_l1(X, REF) == pytest.approx(4 / 21, rel=1e-12)
    assert metrics.rel_l1(REF, REF) == 0.0
    # Negative reference values count by magnitude: Σ|x − r| / Σ|r| = (2 + 0) / (1 + 3).
    assert metrics.rel_l1(np.array([[1.0, 3.0]]), np.array([[-1.0, 3.0]])) == pytest.approx(0.5)


def test_rel_mse_hand_computed():
    expected = (1 / (1 + 0.01) + 9 / (36 + 0.01)) / 6  # mean over all 6 channel values
    assert metrics.rel_mse(X, REF) == pytest.approx(expected, rel=1e-12)
    # The 0.01 keeps black reference pixels finite: x = 0.1 against r = 0 gives 0.01 / 0.01 = 1.
    assert metrics.rel_mse(np.array([[0.1]]), np.array([[0.0]])) == pytest.approx(1.0)
    assert metrics.rel_mse(np.array([[0.1]]), np.array([[0.0]]), eps=0.04) == pytest.approx(0.25)


def test_mask_selects_pixels():
    mask = np.array([[True, False]])
    assert metrics.rel_l1(X, REF, mask) == pytest.approx(1 / 6)
    assert metrics.rel_mse(X, REF, mask) == pytest.approx((1 / 1.01) / 3)
    mask = np.array([[False, True]])
    assert metrics.rel_l1(X, REF, mask) == pytest.approx(3 / 15)
    assert metrics.rel_mse(X, REF, mask) == pytest.approx((9 / 36.01) / 3)


def test_empty_mask_and_black_reference_give_nan():
    none = np.zeros((1, 2), bool)
    assert math.isnan(metrics.rel_l1(X, REF, none))
    assert math.isnan(metrics.rel_mse(X, REF, none))
    assert math.isnan(metrics.rel_l1(X, np.zeros_like(REF)))


def test_alpha_is_ignored():
    x4 = np.concatenate([X, np.full((1, 2, 1), 100.0)], axis=-1)
    r4 = np.concatenate([REF, np.zeros((1, 2, 1))], axis=-1)
    assert metrics.rel_l1(x4, r4) == pytest.approx(4 / 21)
    assert metrics.rel_mse(x4, r4) == pytest.approx(metrics.rel_mse(X, REF))


def test_metrics_agree_with_a_direct_loop_on_random_images():
    rng = np.random.default_rng(1)
    ref = rng.uniform(0, 2, (6, 5, 3))
    x = ref + rng.normal(0, 0.3, ref.shape)
    mask = rng.uniform(size=(6, 5)) > 0.4
    num = den = sq = 0.0
    n = 0
    for i in range(6):
        for j in range(5):
            if not mask[i, j]:
                continue
            for c in range(3):
                num += abs(x[i, j, c] - ref[i, j, c])
                den += abs(ref[i, j, c])
                sq += (x[i, j, c] - ref[i, j, c]) ** 2 / (ref[i, j, c] ** 2 + 0.01)
                n += 1
    assert metrics.rel_l1(x, ref, mask) == pytest.approx(num / den, rel=1e-12)
    assert metrics.rel_mse(x, ref, mask) == pytest.approx(sq / n, rel=1e-12)


def test_relative_error_map():
    err = metrics.relative_error_map(X, REF)
    assert err.shape == (1, 2)
    np.testing.assert_allclose(err[0], [(1 / 1.01) / 3, (3 / 6.01) / 3], rtol=1e-12)


def test_heatmap_ramp():
    vmax = 0.5
    err = np.array([[-1.0, 0.0, vmax / 3, vmax / 2, 2 * vmax / 3, vmax, 10.0]])
    rgb = metrics.heatmap_rgb8(err, vmax=vmax)
    assert rgb.dtype == np.uint8 and rgb.shape == (1, 7, 3)
    assert rgb[0].tolist() == [
        [0, 0, 0],        # below 0 clamps to black
        [0, 0, 0],        # 0 → black
        [255, 0, 0],      # a third → red
        [255, 128, 0],    # half → between red and yellow (g = 0.5 → 128 after rounding)
        [255, 255, 0],    # two thirds → yellow
        [255, 255, 255],  # vmax → white
        [255, 255, 255],  # above vmax clamps to white
    ]
    # Monotone: every channel is non-decreasing along the ramp.
    ramp = metrics.heatmap_rgb8(np.linspace(0, 1, 101), vmax=1.0).astype(int)
    assert (np.diff(ramp, axis=0) >= 0).all()
