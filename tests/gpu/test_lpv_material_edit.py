# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV cached transport: a material edit updates the receivers' albedo without a voxelisation
(lpv/receivers.current_albedo).

A receiver side's albedo is the area-weighted mean of the albedo of the surfaces it sees, so after an edit of
constant-albedo materials it is the albedo before plus, per edited material, the share of the side it covers × its
change. The scene mixes materials inside voxels on purpose: a rug 1 mm over the floor (the floor's top side sees
the rug only) and a poster 1 mm off a wall whose edges cut voxels (their sides see poster and wall).

Against a voxelisation under the edited materials, the update differs by the fixed-point sums' rounding: each piece's
albedo is rounded to 2^-24 of a cell² (voxel/voxelize.py), sliver pieces counted at ≥ 64 units, so a side's mean can
move by ~1e-6 relative, and the float32 weights add ~1e-7. Measured: max |Δ| 7.8e-7 (albedo ≤ 0.9). Bound 1e-5: an
update that mixed up sides, materials or receivers is off by 0.1 or more.
"""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv import receivers
from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.synthetic import box_quads, quad, quad_scene

SETTINGS = RenderSettings("lpv", 48, 36, lpv=LpvSettings(resolution=16, bounces=2))
BOUND = 1e-5


def _room(materials):
    """A white room 4 x 4 x 2.6 m, a rug over its floor, a poster on the far wall, a spot near the ceiling."""
    m = np.linalg.inv(cam.look_at((0.0, -0.6, 2.55), (0.0, 0.4, 0.0), (0, 0, 1)))
    spot = Light("spot", "SPOT", (1, 1, 1), 800.0, m, spot_size=math.radians(60.0), spot_blend=0.2)
    rug = quad([(-1.37, -1.21, 0.001), (1.13, -1.21, 0.001), (1.13, 1.29, 0.001), (-1.37, 1.29, 0.001)], (0, 0, 1))
    poster = quad([(-0.77, 1.999, 0.93), (0.63, 1.999, 0.93), (0.63, 1.999, 1.71), (-0.77, 1.999, 1.71)], (0, -1, 0))
    room = box_quads((-2, -2, 0), (2, 2, 2.6), 0)
    return quad_scene(room + [(rug, 1), (poster, 2)], materials, [spot], (-0.3, -1.85, 1.5), (0.2, 0.6, 0.4),
                      lens=18.0)


BASE = [Material("white", (0.8,) * 3), Material("rug", (0.7, 0.1, 0.05)), Material("poster", (0.1, 0.3, 0.6))]
# Three materials edited at once: two colours, and the rug's metallic, which moves its transport albedo terms.
EDITED = [Material("white", (0.6, 0.7, 0.5)), Material("rug", (0.7, 0.1, 0.05), metallic=0.3),
          Material("poster", (0.9, 0.8, 0.1))]


@pytest.fixture(scope="module")
def engine():
    e = Engine()
    yield e
    e.shutdown()


def _entry(engine, name):
    return engine.pipeline.cache.entries[name].value


def _voxelised(engine, scene):
    """The receivers' albedo of the cached geometry volume, voxelised under `scene`'s materials."""
    gv = _entry(engine, "geometry_volume")[0]
    geometry, textures = _entry(engine, "geometry"), _entry(engine, "textures")
    p = engine.pipeline
    return engine.worker.call(lambda _ctx: receivers.axis_albedo(p.ctx, p.programs, scene, geometry, textures, gv))


def test_a_material_edit_updates_the_albedo_as_a_voxelisation_would(engine):
    engine.render(_room(BASE), SETTINGS)
    gv = _entry(engine, "geometry_volume")[0]
    base_key = gv.materials_key
    edited = _room(EDITED)
    result = engine.render(edited, SETTINGS)
    assert "geometry_volume" in result.skipped and "lpv_albedo" not in result.skipped
    updated = _entry(engine, "lpv_albedo")[0]
    assert gv.materials_key == base_key and sorted(gv.material_weights) == [0, 1, 2]  # the update, not a rebase
    expected = _voxelised(engine, edited)
    diff = np.abs(updated - expected).max()
    print(f"max |update − voxelisation| {diff:.2e} (albedo up to {expected.max():.3f})")
    assert diff <= BOUND
    assert np.abs(updated - gv.surface_albedo).max() > 0.1  # the edit did change the albedo


def test_a_side_s_material_shares_sum_to_one_where_it_sees_a_surface(engine):
    scene = _room(BASE)
    engine.render(scene, SETTINGS)
    gv = _entry(engine, "geometry_volume")[0]
    geometry, textures, p = _entry(engine, "geometry"), _entry(engine, "textures"), engine.pipeline
    shares = engine.worker.call(lambda _ctx: receivers.material_weights(p.ctx, p.programs, scene, geometry, textures, gv,
                                                                   [0, 1, 2]))
    total = sum(shares.values())
    seen = gv.surface_albedo.max(axis=-1) > 0
    mixed = ((shares[2] > 0.05) & (shares[2] < 0.95)).sum()
    print(f"shares: {np.abs(total[seen] - 1).max():.2e} from 1 on {seen.sum()} sides; poster mixed on {mixed}")
    assert np.abs(total[seen] - 1.0).max() <= BOUND and np.abs(total[~seen]).max(initial=0.0) <= BOUND
    assert mixed > 0  # the poster's edges cut voxels: sides that see two materials exist


def test_a_second_edit_of_the_same_materials_voxelises_nothing(engine, monkeypatch):
    engine.render(_room(BASE), SETTINGS)
    engine.render(_room(EDITED), SETTINGS)  # their shares are known now

    def refuse(*args, **kwargs):
        raise AssertionError("voxelised")
    monkeypatch.setattr(receivers, "axis_albedo", refuse)
    again = [Material("white", (0.3, 0.7, 0.9)), EDITED[1], Material("poster", (0.2, 0.2, 0.2))]
    result = engine.render(_room(again), SETTINGS)
    assert "lpv_albedo" not in result.skipped
    monkeypatch.undo()
    cold = Engine()
    try:
        fresh = cold.render(_room(again), SETTINGS)
    finally:
        cold.shutdown()
    di, ref = result.passes["Diffuse Indirect"], fresh.passes["Diffuse Indirect"]
    assert np.abs(di - ref).max() <= 1e-4 * float(ref.mean())  # the albedo's 1e-5, through two bounces


def test_edits_the_update_cannot_follow_are_told_apart():
    rgb = [("rgb", (0.5, 0.5, 0.5)), ("rgb", (0.1, 0.2, 0.3))]
    assert receivers.edited_materials(rgb, [rgb[0], ("rgb", (0.1, 0.2, 0.4))]) == [1]
    assert receivers.edited_materials(rgb, rgb) == []
    assert receivers.edited_materials(None, rgb) is None
    assert receivers.edited_materials(rgb, rgb + [("rgb", (1, 1, 1))]) is None  # a material added
    textured = ("texture", 0, (1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    assert receivers.edited_materials([rgb[0], textured], [rgb[0], textured]) == []
    assert receivers.edited_materials(rgb, [rgb[0], textured]) is None  # a texture now sets its albedo
    assert receivers.edited_materials([rgb[0], textured], [rgb[0], textured[:2] + ((0.5,) * 3, (0.0,) * 3)]) is None
