# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's cached transport after a geometry edit (gpu_kernels/lpv/transfer_update.py): T updated from the one
before it, evaluating again only the pairs the edit can change, gives what a render from scratch gives (to float32
rounding: 1e-5 of the image's mean, as tests/gpu/test_lpv_transfer.py); what it counts as changed:
tests/unit/test_transfer_update.py."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv import transfer_update
from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.lpv_transfer import assert_same, indirect, rerun
from support.synthetic import box_quads, quad_scene, room_with_box

SETTINGS = RenderSettings("lpv", 48, 36, lpv=LpvSettings(resolution=16))



def _slab_test(a: np.ndarray, b: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Whether segments a → b (broadcast, (..., 3)) meet the axis-aligned box (2, 3), in float64."""
    d = b - a
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(d != 0, 1.0 / np.where(d != 0, d, 1.0), 1e30)
    t0, t1 = (box[0] - a) * inv, (box[1] - a) * inv
    enter = np.minimum(t0, t1).max(axis=-1)
    leave = np.maximum(t0, t1).min(axis=-1)
    return (enter <= leave) & (leave >= 0) & (enter <= 1)


@pytest.mark.parametrize("strips", [False, True])
def test_the_pairs_listed_are_those_whose_segment_crosses_a_box(gl, strips):
    """lpv/box_pairs.glsl against a float64 slab test, with the most boxes and 700 sources (when each invocation
    looped over a run of 1024 sources, eight boxes took it past llvmpipe's cap on loop iterations, which silently
    ended the loops: half the crossing pairs went unlisted). Random segments in a 2 m cube; a segment that grazes a
    box's face may come out either way in float32 (≤ 0.1% of the crossing pairs). `strips`: the receivers sorted
    along x, as voxel order makes them, so that most runs of 32 lie away from the boxes and are skipped whole
    (transfer_update.word_spans): those must list what the pair-by-pair test lists."""

    from types import SimpleNamespace

    from bounce_gi.gpu_kernels.gl.bind import ssbo
    from bounce_gi.gpu_kernels.lpv.gather import VPL_DTYPE

    ctx, programs = gl
    rng = np.random.default_rng(7)
    sources, targets = rng.uniform(-1, 1, (700, 3)), rng.uniform(-1, 1, (300, 3))
    if strips:  # 300 receivers along x on a floor, the boxes small: most source–word boxes miss them all
        targets = np.stack([np.linspace(-1, 1, 300), rng.uniform(-0.05, 0.05, 300), np.full(300, -1.0)], axis=1)
    corners = rng.uniform(-0.9, 0.7, (transfer_update.MAX_BOXES, 3))
    boxes = np.stack([corners, corners + rng.uniform(0.1, 0.4, corners.shape)], axis=1)
    records = np.zeros(len(sources), VPL_DTYPE)
    records["position"][:, :3] = sources
    rows = np.zeros((len(targets), 2, 4), np.float32)
    rows[:, 1, :3] = targets
    gv = SimpleNamespace(surface_count=len(targets), receivers=ssbo(ctx, rows), positions=targets)
    clusters = SimpleNamespace(records=records, count=len(records))
    got = transfer_update.box_pairs(ctx, programs, gv, clusters, boxes)
    want = np.any([_slab_test(sources[:, None], targets[None], box) for box in boxes], axis=0)
    print("crossing pairs (GPU, float64), differing:", int(got.sum()), int(want.sum()), int((got != want).sum()))
    assert 0.02 < want.mean() < 0.95 and (got != want).sum() <= 1e-3 * want.sum()
    if strips:  # the skip was taken: most runs' boxes meet no changed box
        spans = transfer_update.word_spans(targets, -(-len(targets) // 32))
        lo = np.minimum(sources[:, None], spans[None, :, 0, :3])
        hi = np.maximum(sources[:, None], spans[None, :, 1, :3])
        near = np.any([(lo <= box[1]).all(-1) & (hi >= box[0]).all(-1) for box in boxes], axis=0)
        print("source–word boxes meeting a changed box:", near.mean())
        assert near.mean() < 0.8
    gv.receivers.release()


def test_moving_an_object_updates_the_transfer_and_matches_a_render_from_scratch(monkeypatch):
    """Moving the box 5 cm re-evaluates only the pairs it can change (a new receiver or source, or a ray through
    the changed box: listed on the GPU, which agrees with a float64 slab test but for segments that graze the box's
    faces, ≤ 0.1% of them) — less than all of T — and gives exactly a cold render's result (float32: 1e-5)."""
    tested, box_pairs = [], transfer_update.box_pairs

    def checked_box_pairs(ctx, programs, gv, clusters, boxes):
        got = box_pairs(ctx, programs, gv, clusters, boxes)
        want = np.any([_slab_test(clusters.records["position"][:, None, :3].astype(np.float64),
                                  np.asarray(gv.positions, np.float64)[None], box) for box in boxes], axis=0)
        tested.append((int(got.sum()), int(want.sum()), int((got != want).sum()), got.size))
        return got
    monkeypatch.setattr(transfer_update, "box_pairs", checked_box_pairs)
    engine = Engine()
    before = engine.render(room_with_box(0.0), SETTINGS)
    moved = engine.render(room_with_box(0.05), SETTINGS)
    print("box pairs (GPU, float64, differing, all):", tested)
    assert len(tested) == 1 and 0 < tested[0][1] < tested[0][3] and tested[0][2] <= 1e-3 * tested[0][1]
    assert np.abs(indirect(moved) - indirect(before)).max() > 1e-3 * indirect(before).mean()  # it did change
    info = moved.info["cascades"][0]
    print("share of T re-evaluated:", info["transfer_updated"])
    assert "lpv_transfer" in rerun(moved) and 0 < info["transfer_updated"] < 0.5
    cold = Engine().render(room_with_box(0.05), SETTINGS)
    assert cold.info["cascades"][0]["block"] == info["block"]
    assert_same(indirect(moved), indirect(cold))


def test_lifting_a_turned_post_lists_the_pairs_near_its_ends_only(monkeypatch):
    """A 1.2 m post turned 20° and lifted 5 cm: its sides stay where they were, but their voxels' areas, normals and
    centroids come out of the float32 arithmetic different in their last bits. Those voxels count as the same
    (transfer_update's tolerances), and the changed cells are split into boxes near the post's two ends
    (changed_boxes), so the segments listed are at most half of those crossing one box around all changed cells
    (measured 0.31 of them; without the tolerances every side voxel changed: four boxes along the whole post,
    0.95); the result is a cold render's."""
    listed, box_pairs = [], transfer_update.box_pairs

    def counted_box_pairs(ctx, programs, gv, clusters, boxes):
        got = box_pairs(ctx, programs, gv, clusters, boxes)
        around = np.stack([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])
        one = _slab_test(clusters.records["position"][:, None, :3].astype(np.float64),
                         np.asarray(gv.positions, np.float64)[None], around)
        listed.append((len(boxes), int(got.sum()), int(one.sum())))
        return got
    monkeypatch.setattr(transfer_update, "box_pairs", counted_box_pairs)
    engine = Engine()
    engine.render(room_with_box(0.0, size=0.3, height=1.2, turn=20.0), SETTINGS)
    moved = engine.render(room_with_box(0.05, size=0.3, height=1.2, turn=20.0), SETTINGS)
    print("boxes, pairs listed, pairs crossing one box around them:", listed)
    assert len(listed) == 1 and listed[0][0] > 1 and listed[0][1] <= 0.5 * listed[0][2]
    assert_same(indirect(moved), indirect(Engine().render(room_with_box(0.05, size=0.3, height=1.2, turn=20.0),
                                                      SETTINGS)))


def test_an_edit_that_changes_most_of_the_transfer_builds_it_anew_without_updating(monkeypatch):
    """A 1.2 m box lifted 30 cm changes more than half of T's pairs: with the rebuild share at a half, T is made
    anew (the share reads 1), and no pair is evaluated for an update first (the courtyard's object move paid for
    both)."""
    evaluated, updates, update = [], [], transfer_update.update_transfer
    monkeypatch.setattr(transfer_update, "REBUILD_SHARE", 0.5)
    monkeypatch.setattr(transfer_update, "evaluate_pairs", lambda *a: evaluated.append(len(a[-1])))
    monkeypatch.setattr(transfer_update, "update_transfer", lambda *a, **k: updates.append(update(*a, **k)))
    engine = Engine()
    engine.render(room_with_box(0.0, size=1.2), SETTINGS)
    moved = engine.render(room_with_box(0.3, size=1.2), SETTINGS)
    assert "lpv_transfer" in rerun(moved) and moved.info["cascades"][0]["transfer_updated"] == 1.0
    assert updates == [None] and evaluated == []  # an update was tried, and gave up before evaluating a pair
    assert_same(indirect(moved), indirect(Engine().render(room_with_box(0.3, size=1.2), SETTINGS)))


def test_an_edit_that_changes_over_half_of_the_transfer_still_updates_it():
    """The same edit with the default rebuild share (transfer_update.REBUILD_SHARE: a pair costs an update what it
    costs a build): T is updated, over half of it evaluated again, and gives a cold render's result."""
    engine = Engine()
    engine.render(room_with_box(0.0, size=1.2), SETTINGS)
    moved = engine.render(room_with_box(0.3, size=1.2), SETTINGS)
    share = moved.info["cascades"][0]["transfer_updated"]
    print("share of T re-evaluated:", share)
    assert "lpv_transfer" in rerun(moved) and 0.5 < share < transfer_update.REBUILD_SHARE
    assert_same(indirect(moved), indirect(Engine().render(room_with_box(0.3, size=1.2), SETTINGS)))


def _room_with_plate(z):
    """The room of _room with a 0.6 m square plate (a table top, both sides) floating `z` m above the floor."""
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),)) + \
        box_quads((-0.2, -0.2, z), (0.4, 0.4, z), 1, inward=False, skip=((0, "lo"), (0, "hi"), (1, "lo"), (1, "hi")))
    bulb = np.eye(4)
    bulb[:3, 3] = (-0.4, 0.2, 1.4)
    return quad_scene(quads, [Material("floor", (0.7, 0.7, 0.7)), Material("plate", (0.8, 0.3, 0.2))],
                      [Light("bulb", "POINT", (1, 1, 1), 60.0, bulb)], (0.0, -0.95, 1.0), (0.0, 0.5, 0.6),
                      lens=12.0)


def test_a_move_within_the_voxels_updates_the_pairs_it_moves():
    """A plate lifted 1 cm, within its voxels: they keep their cells, normals and areas, but the surfaces lie
    elsewhere in them (the receivers' positions, the clusters' records, the visibility planes), so the transfer's
    update must still re-evaluate their pairs — it gives a cold render's result."""
    engine = Engine()
    engine.render(_room_with_plate(0.52), SETTINGS)
    moved = engine.render(_room_with_plate(0.53), SETTINGS)
    assert "lpv_transfer" in rerun(moved) and moved.info["cascades"][0]["transfer_updated"] < 1.0
    assert_same(indirect(moved), indirect(Engine().render(_room_with_plate(0.53), SETTINGS)))


def test_the_second_update_writes_into_the_memory_of_the_transfer_it_evicts():
    """The box lifted 5 cm and again: two transfers are kept (lpv/passes.KEEP), so the second update's T goes into
    the memory of the first T, which it evicts (PassCache.spare, transfer.empty_matrix) rather than into new
    memory, and still gives a cold render's result."""
    engine = Engine()
    try:
        matrix = lambda: engine.pipeline.cache.entries["lpv_transfer"].value[0].matrix  # noqa: E731
        engine.render(room_with_box(0.0), SETTINGS)
        first = matrix()
        engine.render(room_with_box(0.05), SETTINGS)
        assert not np.shares_memory(matrix(), first)
        second = engine.render(room_with_box(0.10), SETTINGS)
        assert 0 < second.info["cascades"][0]["transfer_updated"] < 0.5 and np.shares_memory(matrix(), first)
        assert_same(indirect(second), indirect(Engine().render(room_with_box(0.10), SETTINGS)))
    finally:
        engine.shutdown()


def test_an_update_that_would_outgrow_the_memory_budget_builds_anew(monkeypatch):
    """Re-made with the prior's blocks, the clusters may outnumber what transfer_mb allows for the new receivers
    (a build picks larger blocks): the update gives up before evaluating a pair, and T is built anew. Here the
    budget the update is given is one cluster."""
    results, update = [], transfer_update.update_transfer

    def tight(*a, **k):
        results.append(update(*a, **{**k, "most_clusters": 1}))
        return results[-1]
    monkeypatch.setattr(transfer_update, "update_transfer", tight)
    monkeypatch.setattr(transfer_update, "evaluate_pairs", lambda *a: pytest.fail("no pair is evaluated"))
    engine = Engine()
    engine.render(room_with_box(0.0), SETTINGS)
    moved = engine.render(room_with_box(0.05), SETTINGS)
    assert results == [None] and moved.info["cascades"][0]["transfer_updated"] == 1.0
