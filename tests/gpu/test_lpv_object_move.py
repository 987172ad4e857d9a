# SPDX-License-Identifier: GPL-3.0-or-later
"""An object's move in the LPV's cached transport: what it draws, voxelises and records again is only what the move
can change, and the result is a cold render's (the transfer's update: tests/gpu/test_lpv_transfer_update.py)."""
from dataclasses import replace

import numpy as np

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv import gather, regional
from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.lpv_transfer import assert_same, indirect
from support.synthetic import room_with_box

SETTINGS = RenderSettings("lpv", 48, 36, lpv=LpvSettings(resolution=16))



def test_an_objects_move_voxelises_only_the_region_it_changed(monkeypatch):
    """The box moved 5 cm: the geometry volume voxelises again only the voxels the box left and entered, grown by
    one (lpv/regional.py: under a tenth of the fine grid here), into its kept voxelisation — and its receivers are a
    cold render's, byte for byte, and so is the light (to float32 rounding, like every cached edit)."""
    regions, moved_region = [], regional.moved_region
    monkeypatch.setattr(regional, "moved_region", lambda *a: regions.append(moved_region(*a)) or regions[-1])
    engine, cold = Engine(), Engine()
    engine.render(room_with_box(0.0), SETTINGS)
    moved = engine.render(room_with_box(0.05), SETTINGS)
    fresh = cold.render(room_with_box(0.05), SETTINGS)
    assert regions[0] is None and regions[2] is None  # nothing kept before the first render of an engine
    gv, gv_cold = (e.pipeline.cache.entries["geometry_volume"].value[0] for e in (engine, cold))
    lo, hi = regions[1]
    assert 0 < np.prod(hi - lo) < 0.1 * np.prod(gv.fine.size)
    share = np.prod(hi - lo) / np.prod(gv.fine.size)
    assert moved.info["cascades"][0]["voxelised"] == share and fresh.info["cascades"][0]["voxelised"] == 1.0
    for name in ("cells", "axis", "surface_normal", "surface_area", "positions", "surface_albedo"):
        assert np.array_equal(getattr(gv, name), getattr(gv_cold, name)), name
    assert np.array_equal(gv.bounds[0], gv_cold.bounds[0]) and np.array_equal(gv.bounds[1], gv_cold.bounds[1])
    assert_same(indirect(moved), indirect(fresh))


def test_an_objects_move_makes_again_only_the_records_of_the_texels_it_covers(monkeypatch):
    """The box moved 5 cm: the RSM is drawn again only where the box was and is (rsm.render_rsm), and only those
    texels' records are made again (passes.texel_records) and merged with the kept ones in the order a run over the
    whole atlas gives (gather.merge_records) — a cold render's records, byte for byte, and its light. A sun besides
    the bulb: an orthographic view as well as a cube's."""
    calls, rsm_records = [], gather.rsm_records
    monkeypatch.setattr(gather, "rsm_records", lambda *a, **k: calls.append(k.get("blocks")) or rsm_records(*a, **k))
    sun = np.eye(4)
    sun[:3, :3] = [[1, 0, 0], [0, 0.8, -0.6], [0, 0.6, 0.8]]  # −z turned 37° towards +y

    def scene(z):
        return replace(room_with_box(z), lights=room_with_box(z).lights + [Light("sun", "SUN", (1, 1, 1), 2.0, sun)])
    engine, cold = Engine(), Engine()
    engine.render(scene(0.0), SETTINGS)
    moved = engine.render(scene(0.05), SETTINGS)
    fresh = cold.render(scene(0.05), SETTINGS)
    assert calls[0] is None and calls[2] is None  # nothing to keep in an engine's first render
    print("blocks whose records were made again:", int(calls[1].sum()), "of", calls[1].size)
    assert 0 < calls[1].sum() < 0.5 * calls[1].size
    kept, new = (e.pipeline.cache.entries["lpv_inject"].value.records[0] for e in (engine, cold))
    assert np.array_equal(kept[1], new[1]) and kept[0].tobytes() == new[0].tobytes()
    assert_same(indirect(moved), indirect(fresh))


def test_a_material_given_to_an_object_is_drawn_into_the_kept_maps():
    """The box given a third material, nothing moved: the RSM holds each texel's material, so the texels of the
    triangles whose material (or normals, or UVs) changed are drawn again like a moved object's — the light is a
    cold render's."""
    def scene(material):
        s = room_with_box(0.0)
        mats = np.where(s.material_index == 1, material, s.material_index).astype(np.int32)
        return replace(s, material_index=mats, materials=s.materials + [Material("blue", (0.1, 0.2, 0.9))])
    engine = Engine()
    before = engine.render(scene(1), SETTINGS)
    after = engine.render(scene(2), SETTINGS)
    assert np.abs(indirect(after) - indirect(before)).max() > 1e-3 * indirect(before).mean()  # it did change
    assert_same(indirect(after), indirect(Engine().render(scene(2), SETTINGS)))


def test_an_object_moved_out_of_every_view_keeps_every_record(monkeypatch):
    """A spot light shining at the far corner of the floor, the box moved by the other wall, out of its cone: no
    texel of its maps is drawn again and every record is kept as it was (none made) — and the light is a cold
    render's, the transfer's update carrying the box's own change."""
    calls, rsm_records = [], gather.rsm_records
    monkeypatch.setattr(gather, "rsm_records", lambda *a, **k: calls.append(k.get("blocks")) or rsm_records(*a, **k))
    spot = np.eye(4)  # at (−0.6, −0.6, 1.8), shining straight down, a 30° cone: the floor's far corner
    spot[:3, 3] = (-0.6, -0.6, 1.8)

    def scene(z):
        s = room_with_box(z)
        return replace(s, lights=[Light("spot", "SPOT", (1, 1, 1), 80.0, spot, spot_size=np.radians(30.0))])
    engine = Engine()
    engine.render(scene(0.0), SETTINGS)
    moved = engine.render(scene(0.05), SETTINGS)
    assert len(calls) == 1  # the first render's; the move made none
    assert engine.pipeline.cache.entries["rsm"].value.redrawn == []
    assert_same(indirect(moved), indirect(Engine().render(scene(0.05), SETTINGS)))
