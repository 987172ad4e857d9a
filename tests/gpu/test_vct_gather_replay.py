# SPDX-License-Identifier: GPL-3.0-or-later
"""The bounce gathers record the steps that absorbed light once per geometry (vct/bounce.gather_pool, vct/hits.glsl
GatherStep) and replay them in later gathers — the next bounces of the same frame and every bounce after a light
edit. A replay sums the same float32 terms in the same order as the gather, so the bounced light must be bit for bit
what plain gathers of the same volumes give, also where the pool could not keep every face's steps."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.gl.pass_cache import release_resources
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct import bounce, replay
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.synthetic import box_quads, quad_scene

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))


def _room(lamp=(-0.3, 0.2, 1.5), block=(0.8, 0.2, 0.1)):
    matrix = np.eye(4)
    matrix[:3, 3] = lamp
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    quads += box_quads((-0.3, -0.3, 0.0), (0.3, 0.3, 0.7), 1, inward=False)
    return quad_scene(quads, [Material("white", (0.7, 0.7, 0.7)), Material("block", block)],
                      [Light("bulb", "POINT", (1, 1, 1), 60.0, matrix)], (0.0, -0.9, 1.5), (0.0, 0.5, 0.3))


def _gathered_plainly(engine, scene, monkeypatch):
    """The same frame's bounces again with plain gathers (no pool): vct_bounce and what follows it dropped."""
    def drop(ctx):
        for name in ("vct_bounce", "vct_trace", "vct_hits", "vct_upsample", "vct_specular", "compose", "vct_scale"):
            entry = engine.pipeline.cache.entries.pop(name, None)
            if entry is not None:
                release_resources(entry.value)
    engine.worker.call(drop)
    with monkeypatch.context() as m:
        m.setattr(bounce, "gather_pool", lambda *args: None)
        return engine.render(scene, SETTINGS)


@pytest.mark.parametrize("per_face", [replay.CHUNKS_PER_FACE, 0.05], ids=["pool", "pool too small"])
def test_replayed_gathers_are_the_gathers(monkeypatch, per_face):
    monkeypatch.setattr(replay, "CHUNKS_PER_FACE", per_face)
    engine = Engine()
    try:
        engine.render(_room(), SETTINGS)
        pool = engine.pipeline.cache.entries["vct_geometry"].value.gather_pool
        assert pool.recorded and (pool.needed <= pool.capacity) == (per_face >= 1)
        edited = _room(lamp=(0.5, -0.4, 1.2))
        replayed = engine.render(edited, SETTINGS)  # every bounce replayed
        assert engine.pipeline.cache.entries["vct_geometry"].value.gather_pool is pool
        plain = _gathered_plainly(engine, edited, monkeypatch)
        assert "vct_inject" in plain.skipped and "vct_bounce" not in plain.skipped
        for name in ("Diffuse Indirect", "Combined"):
            assert np.array_equal(replayed.passes[name], plain.passes[name]), name
        assert [b["flux"] for b in replayed.info["bounces"]] == [b["flux"] for b in plain.info["bounces"]]
    finally:
        engine.shutdown()


def test_a_black_surface_made_bright_is_gathered_anew(monkeypatch):
    """A face without albedo is not gathered, so the first gather records nothing for the black block's faces; once
    its colour is bright, a replay gathers them (their records marked absent), as plain gathers do."""
    engine = Engine()
    try:
        engine.render(_room(block=(0.0, 0.0, 0.0)), SETTINGS)
        edited = _room(block=(0.8, 0.2, 0.1))
        replayed = engine.render(edited, SETTINGS)
        assert "vct_geometry" in replayed.skipped
        plain = _gathered_plainly(engine, edited, monkeypatch)
        for name in ("Diffuse Indirect", "Combined"):
            assert np.array_equal(replayed.passes[name], plain.passes[name]), name
    finally:
        engine.shutdown()


def test_the_record_orders_each_run_of_faces_by_its_steps(monkeypatch):
    """After the record, the face list and the pool's headers are permuted alike (bounce.order_by_steps): within each
    run of ORDER_BLOCK entries the faces with the most recorded steps come first, and the list still holds every
    face with coverage once (the replays equal plain gathers: test_replayed_gathers_are_the_gathers)."""
    monkeypatch.setattr(bounce, "ORDER_BLOCK", 64)

    def read(listed, pool, count):
        headers = np.frombuffer(pool.headers.read(size=16 * count), np.uint32).reshape(count, 4).copy()
        return headers, np.frombuffer(listed.read(size=16 * count), np.int32).reshape(count, 4).copy()

    recorded = []  # each face's header as the record left it, before the reorder
    order = bounce.order_by_steps
    monkeypatch.setattr(bounce, "order_by_steps",
                        lambda listed, pool, count: (recorded.append(read(listed, pool, count)),
                                                     order(listed, pool, count)))
    engine = Engine()
    try:
        engine.render(_room(), SETTINGS)
        shared = engine.pipeline.cache.entries["vct_geometry"].value
        listed, count = shared.face_list
        headers, entries = engine.worker.call(lambda ctx: read(listed, shared.gather_pool, count))
        steps = headers[:, 1].astype(np.int64)
        assert len(recorded) == 1 and count > 4 * 64 and len(np.unique(steps)) > 10
        runs = steps[: count // 64 * 64].reshape(-1, 64)
        assert (np.diff(runs, axis=1) <= 0).all()
        assert not (np.diff(steps) <= 0).all()  # runs, not one sort over the whole list
        headers0, entries0 = recorded[0]
        before = {tuple(e): tuple(h) for e, h in zip(entries0, headers0)}  # each face keeps its own header
        assert len(before) == count and {tuple(e): tuple(h) for e, h in zip(entries, headers)} == before
    finally:
        engine.shutdown()
