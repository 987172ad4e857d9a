# SPDX-License-Identifier: GPL-3.0-or-later
"""The sky's penumbra filter (direct/sky_filter.glsl via direct/sky.filter_sky_shares), driven with a G-buffer
we choose: a floor beside a wall, 2 cm per pixel. A step in the floor's sky share (an opening's edge seen through
one direction) must come back as the box average over each pixel's penumbra half-width of the floor's own pixels
only — exactly, in float32 — and the wall beside it, whose share differs, must neither take nor give any. The glossy
share is left as tested (a glossy reflection is as sharp as its lobe, not as wide as the penumbra)."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.direct.gbuffer import GBuffer
from bounce_gi.gpu_kernels.direct.sky import filter_sky_shares

W, H = 64, 16
FLOOR = 32          # columns 0..31: the floor (z = 0, normal +z); 32..63: a wall (x = 0.64 m, normal −x)
PIXEL = 0.02        # m per pixel on the floor
EDGE = 16           # the floor's share is 1 left of this column, 0 from it on
HALF_WIDTH = 0.1    # m: the penumbra's half-width every pixel carries (5 pixels on the floor)


def _inputs(half_width):
    i, j = np.meshgrid(np.arange(W), np.arange(H))
    floor = i < FLOOR
    position = np.zeros((H, W, 4), np.float32)
    position[..., 0] = np.where(floor, (i + 0.5) * PIXEL, FLOOR * PIXEL)
    position[..., 1] = (j + 0.5) * PIXEL
    position[..., 2] = np.where(floor, 0.0, (i - FLOOR + 0.5) * PIXEL)
    position[..., 3] = 1.0
    normal = np.zeros((H, W, 4), np.float32)
    normal[floor, 2] = 1.0
    normal[~floor, 0] = -1.0
    shares = np.zeros((H, W, 4), np.float32)
    shares[..., 0] = np.where(floor, (i < EDGE).astype(np.float32), 0.5)
    shares[..., 1] = shares[..., 0] * 0.25
    shares[..., 2] = half_width
    return position, normal, shares


def _filter(gl, half_width):
    ctx, programs = gl
    position, normal, shares = _inputs(half_width)
    textures = {"position": ctx.texture((W, H), 4, position.tobytes(), dtype="f4"),
                "geo_normal": ctx.texture((W, H), 4, normal.tobytes(), dtype="f4")}
    source = ctx.texture((W, H), 4, shares.tobytes(), dtype="f4")
    out = filter_sky_shares(ctx, programs, GBuffer(textures, None, None, (W, H)), source)
    result = np.frombuffer(out.read(), np.float32).reshape(H, W, 4)
    assert np.array_equal(np.frombuffer(source.read(), np.float32).reshape(H, W, 4), shares)  # kept as it was
    out.release()
    source.release()
    for t in textures.values():
        t.release()
    return result, shares


def test_a_step_becomes_the_box_average_of_its_own_surface(gl):
    got, shares = _filter(gl, HALF_WIDTH)
    radius = round(HALF_WIDTH / PIXEL)
    expected = shares[..., 0].copy()
    for i in range(FLOOR):  # the window clipped to the floor: the wall's pixels are another surface
        window = shares[0, max(i - radius, 0):min(i + radius + 1, FLOOR), 0]
        expected[:, i] = window.mean()
    np.testing.assert_allclose(got[..., 0], expected, atol=1e-6)
    assert np.array_equal(got[..., 1], shares[..., 1])  # the glossy share as tested
    assert got[0, EDGE, 0] == pytest.approx(5 / 11, abs=1e-6)  # 5 of its 11 pixels lit
    assert np.all(got[:, FLOOR:, 0] == 0.5)  # the wall neither took the floor's light nor gave its own
    assert np.all(got[..., 2] == np.float32(HALF_WIDTH))


def test_no_penumbra_leaves_the_shares_as_they_are(gl):
    got, shares = _filter(gl, 0.0)
    assert np.array_equal(got, shares)
