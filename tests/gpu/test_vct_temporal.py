# SPDX-License-Identifier: GPL-3.0-or-later
"""Temporal accumulation of the VCT diffuse gather (gpu_kernels/vct/temporal.py): repeated renders of an unchanged scene each
add one frame with the cone set turned about the normal; the history is the mean of the frames; any change of the
trace's inputs restarts it (no ghost of the old scene) — but an edit that scales every light alike, which the trace
reads per unit of the lights' colour (vct/colours.py), keeps it."""
import dataclasses

import numpy as np
import pytest

from bounce_gi.gpu_kernels.vct import temporal as vct_temporal
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from test_vct import _sunlit_room

N = 8


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _settings(**kw):
    return RenderSettings("vct", 64, 48, vct=VctSettings(**{"resolution": 32, **kw}))


def test_jitter_sequence():
    s = VctSettings(diffuse_cones=6, cone_rotation=5.0)
    # Frame 0 unturned (so the first frame is a plain render); then van der Corput fractions of the 72° spacing.
    assert [vct_temporal.jitter_deg(s, k) for k in range(4)] == [5.0, 41.0, 23.0, 59.0]
    assert vct_temporal.frame_index(None, ("a",), 8) == 0
    h = vct_temporal.History(None, ("a",), frames=8)
    assert vct_temporal.frame_index(h, ("a",), 8) == 7 and vct_temporal.frame_index(h, ("b",), 8) == 0


@pytest.mark.parametrize("scale", [1, 2])
def test_accumulation_is_the_mean_of_the_jittered_frames_and_converges(engine, scale):
    scene = _sunlit_room()
    settings = _settings(temporal_frames=N, indirect_scale=scale)
    history = []
    for k in range(N + 2):
        r = engine.render(scene, settings)
        history.append(r.passes["Diffuse Indirect"].astype(np.float64))
        t = r.info["temporal"]
        assert t["frames"] == min(k + 1, N) and t["of"] == N and t["done"] == (k + 1 >= N)
        if k >= N:  # complete: the trace, upsampling and accumulation are skipped, the image holds still
            assert {"vct_trace", "vct_accumulate"} <= set(r.skipped)
            np.testing.assert_array_equal(history[-1], history[N - 1])
        else:
            assert "vct_trace" not in r.skipped
    # The same frames rendered one at a time (accumulation off, the cone set turned by frame k's angle).
    frames = []
    for k in range(N):
        rot = vct_temporal.jitter_deg(settings.vct, k)
        single = engine.render(scene, dataclasses.replace(settings, vct=dataclasses.replace(
            settings.vct, temporal_frames=0, cone_rotation=rot)))
        frames.append(single.passes["Diffuse Indirect"].astype(np.float64))
    frames = np.array(frames)
    scale_ = np.abs(frames).mean()
    # Running mean in float32 against the float64 mean of the same float32 frames: 1e-5 of the mean level.
    for k in range(N):
        err = np.abs(history[k] - frames[:k + 1].mean(axis=0)).max()
        assert err < 1e-5 * max(scale_, 1e-6), (k, err)
    # The jitter changes the frames (else there is nothing to accumulate), and the running mean settles: each step
    # moves it by (C_k − A_{k−1}) / (k + 1).
    steps = [np.abs(history[k] - history[k - 1]).mean() / scale_ for k in range(1, N)]
    spread = np.abs(frames - frames.mean(axis=0)).mean() / scale_
    print(f"scale {scale}: frame spread about the mean {spread:.4f}; running-mean steps "
          f"{[round(float(x), 5) for x in steps]}")
    assert spread > 1e-3
    assert steps[-1] < 0.5 * steps[0] and max(steps[N // 2:]) < steps[0]


def test_any_change_restarts_the_history_without_a_ghost(engine):
    scene = _sunlit_room()
    settings = _settings(temporal_frames=N)
    for _ in range(N):
        engine.render(scene, settings)
    # The sun twice as strong scales the whole transport (vct/colours.py): the complete history is kept, scaled.
    complete = engine.render(scene, settings)
    sun = scene.lights[0]
    brighter = dataclasses.replace(scene, lights=[dataclasses.replace(sun, power=2.0 * sun.power)])
    r = engine.render(brighter, settings)
    assert r.info["temporal"]["frames"] == N and "vct_trace" in r.skipped
    np.testing.assert_allclose(r.passes["Diffuse Indirect"], 2.0 * complete.passes["Diffuse Indirect"], rtol=1e-6)
    # A change of the scene (the sun turned 10°), of the camera, and of the trace settings: each first frame
    # equals a fresh render of the new state (frame 0: the unturned cone set, i.e. accumulation off).
    c, s_ = np.cos(np.radians(10.0)), np.sin(np.radians(10.0))
    turn = np.array([[1, 0, 0, 0], [0, c, -s_, 0], [0, s_, c, 0], [0, 0, 0, 1.0]])
    turned = dataclasses.replace(brighter, lights=[dataclasses.replace(sun, matrix_world=sun.matrix_world @ turn)])
    moved = dataclasses.replace(turned, camera=dataclasses.replace(
        turned.camera, matrix_world=turned.camera.matrix_world @ np.array(
            [[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])))
    fresh = Engine()
    for changed, s in ((turned, settings), (moved, settings), (moved, _settings(temporal_frames=N, ao_distance=0.5))):
        r = engine.render(changed, s)
        assert r.info["temporal"]["frames"] == 1
        # (a full trace: without reuse_reach 0 the camera move would take the turned view's gathers, vct/reuse.py)
        plain = fresh.render(changed, dataclasses.replace(s, vct=dataclasses.replace(s.vct, temporal_frames=0,
                                                                                      reuse_reach=0.0)))
        for name in ("Diffuse Indirect", "AO", "Combined"):
            np.testing.assert_allclose(r.passes[name], plain.passes[name], rtol=1e-6, atol=1e-7)
        r2 = engine.render(changed, s)  # and it accumulates from there
        assert r2.info["temporal"]["frames"] == 2
