# SPDX-License-Identifier: GPL-3.0-or-later
"""The per-pixel trace's hits are recorded once and replayed after a light or world edit (vct/replay.py,
vct/hits.glsl): the replay must give the image a trace of the same volumes gives, bit for bit — it sums the same
float32 terms in the same order — also when the pool could not hold every texel's hits (those are traced again);
an edit that moves geometry or the camera records anew. The comparison is with a trace of the same volumes, not a
cold render: the injection's float sums may differ in the last bit from run to run (vct/inject_raster.glsl)."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct import replay
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from bounce_gi.gpu_kernels.vct.trace import read_texture
from support.synthetic import box_quads, quad_scene

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))


def _room(lamp=(-0.3, 0.2, 1.5), block=0.0, world=(0.0, 0.0, 0.0), eye=(0.0, -0.9, 1.5), red=(0.8, 0.2, 0.1)):
    """An open-topped room (the world shows through it) with a block and a point lamp."""
    matrix = np.eye(4)
    matrix[:3, 3] = lamp
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    quads += box_quads((-0.3 + block, -0.3, 0.0), (0.3 + block, 0.3, 0.7), 1, inward=False)
    return quad_scene(quads, [Material("white", (0.7, 0.7, 0.7)), Material("red", red)],
                      [Light("bulb", "POINT", (1, 1, 1), 60.0, matrix)], eye, (0.0, 0.5, 0.3), world=world)


def _traced(engine):
    """(the vct_trace texture as floats, whether it was replayed, the pool)."""
    def grab(ctx):
        value = engine.pipeline.cache.entries["vct_trace"].value
        return read_texture(value["indirect"], 4).copy(), value["replayed"]
    image, replayed = engine.worker.call(grab)
    return image, replayed, engine.pipeline.cache.entries["vct_hits"].value


def _trace_again(engine, scene):
    """Drop the trace and its hits, render `scene` again: the trace runs (and records) on the same volumes."""
    def drop(ctx):
        for name in ("vct_trace", "vct_hits"):
            entry = engine.pipeline.cache.entries.pop(name)
            entry.value["indirect"].release() if name == "vct_trace" else entry.value.release()
    engine.worker.call(drop)
    engine.render(scene, SETTINGS)
    return _traced(engine)


@pytest.mark.parametrize("edit", [dict(lamp=(0.5, -0.4, 1.2)), dict(world=(0.4, 0.5, 0.7)),
                                  dict(red=(0.1, 0.6, 0.2))], ids=["light move", "world colour", "material colour"])
def test_a_light_edit_replays_the_trace_bit_for_bit(edit):
    engine = Engine()
    try:
        first = engine.render(_room(), SETTINGS)
        image, replayed, pool = _traced(engine)
        assert not replayed and pool.recorded and pool.needed <= pool.capacity
        assert first.info["trace_hits"]["all_kept"]
        edited = _room(**edit)
        result = engine.render(edited, SETTINGS)
        assert "vct_trace" not in result.skipped and "vct_hits" in result.skipped
        replayed_image, replayed, _ = _traced(engine)
        assert replayed and not np.array_equal(replayed_image, image)  # the light changed, and the replay shows it
        traced_image, replayed, _ = _trace_again(engine, edited)
        assert not replayed
        assert np.array_equal(replayed_image, traced_image)
    finally:
        engine.shutdown()


def test_texels_the_pool_cannot_hold_are_traced_again(monkeypatch):
    """A pool of a twentieth of the hits: most texels are not kept, and a replay traces them."""
    engine = Engine()
    try:
        engine.render(_room(), SETTINGS)
        _, _, pool = _traced(engine)
        budget = replay.HEADER_BYTES * 40 * 30 + replay.chunk_bytes(replay.TRACE_SLOTS) * max(pool.needed // 20, 1)
        monkeypatch.setattr(replay, "BUDGET_BYTES", budget)
        engine.shutdown()
        engine = Engine()
        first = engine.render(_room(), SETTINGS)
        assert not first.info["trace_hits"]["all_kept"]
        edited = _room(lamp=(0.5, -0.4, 1.2))
        engine.render(edited, SETTINGS)
        replayed_image, replayed, small = _traced(engine)
        assert replayed and small.needed > small.capacity
        traced_image, _, _ = _trace_again(engine, edited)
        assert np.array_equal(replayed_image, traced_image)
    finally:
        engine.shutdown()


@pytest.mark.parametrize("edit", [dict(block=0.2), dict(eye=(0.1, -0.9, 1.4))], ids=["object move", "camera"])
def test_moving_geometry_or_the_camera_records_anew(edit):
    """With reuse off: a camera move whose view takes the last one's gathers (vct/reuse.py) traces only part of it
    and records no hits; tests/gpu/test_vct_reuse.py covers that path."""
    settings = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32, reuse_reach=0.0))
    engine = Engine()
    try:
        engine.render(_room(), settings)
        _, _, before = _traced(engine)
        result = engine.render(_room(**edit), settings)
        _, replayed, after = _traced(engine)
        assert not replayed and after is not before and after.recorded
        assert "vct_hits" not in result.skipped
        # sized from the last record: a quarter more than it needed per texel, plus one chunk
        assert after.capacity == int((1.25 * before.needed / (20 * 15) + 1.0) * 20 * 15)
    finally:
        engine.shutdown()


def test_the_viewport_stages_replay_after_a_light_move():
    """The live viewport renders a draft (coarser grid) and a final stage on surface atlases after every edit: each
    stage's hits are kept through the other's, so after a light move both replay."""
    from bounce_gi.ui.live import draft_settings

    final = RenderSettings("vct", 64, 64, vct=VctSettings(resolution=32))
    draft = draft_settings(final)
    assert draft.vct != final.vct  # fewer cones and sub-rays (and a coarser grid at larger resolutions)
    engine = Engine()
    try:
        for scene in (_room(), _room(lamp=(0.5, -0.4, 1.2))):
            replayed = []
            for settings, budget in ((draft, 4096), (final, 16384)):
                engine.submit_surface(scene, settings, budget).result()
                replayed.append(engine.pipeline.cache.entries["vct_trace"].value["replayed"])
        assert replayed == [True, True]
    finally:
        engine.shutdown()
