# SPDX-License-Identifier: GPL-3.0-or-later
"""The VCT injection lights the voxel faces that caught no raster sample (slivers) in a pass of their own, over a
list the resolve makes (vct/inject.py, vct/inject.glsl MODE_FALLBACK): every such face is listed and lit, also when
the list had to be made again larger than its first guess, and lit as the face centre's direct light says."""
import numpy as np

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct import inject
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from bounce_gi.gpu_kernels.vct.trace import read_level
from support.synthetic import box_quads, quad_scene

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))


def _room():
    """A closed room lit by a point lamp, with a thin slab standing in it: its sides are slivers of its voxels."""
    bulb = np.eye(4)
    bulb[:3, 3] = (-0.3, 0.2, 1.5)
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0)
    quads += box_quads((0.2, -0.5, 0.0), (0.203, 0.5, 1.1), 1, inward=False)
    return quad_scene(quads, [Material("white", (0.7, 0.7, 0.7)), Material("red", (0.8, 0.2, 0.1))],
                      [Light("bulb", "POINT", (1, 1, 1), 60.0, bulb)], (0.0, -0.9, 1.5), (0.0, 0.5, 0.3))


def _render(monkeypatch, room=None):
    """(the six injected face volumes, level 0, as (6, z, y, x, 4); their centroids' w; the counts listed; the
    result; the grid)."""
    counts = []
    counted = inject.dispatch_counted

    def spy(*args, **kwargs):
        counts.append(counted(*args, **kwargs))
        return counts[-1]
    monkeypatch.setattr(inject, "dispatch_counted", spy)
    if room is not None:
        monkeypatch.setattr(inject, "LISTED_ROOM", room)
    engine = Engine()
    try:
        result = engine.render(_room(), SETTINGS)
        pipe = engine.pipeline

        def grab(ctx):
            faces = pipe.cache.entries["vct_inject"].value
            lit = np.stack([read_level(ctx, pipe.programs, t, faces.grid, 0) for t in faces.textures])
            where = np.stack([read_level(ctx, pipe.programs, t, faces.grid, 0)[..., 3] for t in faces.centroids])
            return lit, where, faces.grid
        lit, where, grid = engine.worker.call(grab)
    finally:
        engine.shutdown()
    return lit, where, counts, result, grid


def test_every_fallback_face_is_listed_and_lit(monkeypatch):
    lit, where, counts, result, grid = _render(monkeypatch)
    fallback = where < 0  # vct/inject.glsl: a fallback face's centroid has w = −α
    # Listed twice, the same faces: by the albedo's resolve (vct/face_albedo.glsl) and by the light's.
    assert counts == [int(fallback.sum())] * 2 and counts[0] == result.info["faces_without_samples"]
    # Lit at the face's centre, n·cell/2 out of the voxel: those of the slab's sides, inside the room and facing the
    # lamp, get its light (nothing stands between); those whose point lies outside the room's walls get none.
    lamp = np.array([-0.3, 0.2, 1.5])
    inside = outside = 0
    for g in range(6):
        n = np.zeros(3)
        n[g >> 1] = 1.0 if g % 2 == 0 else -1.0
        for z, y, x in np.argwhere(fallback[g]):
            p = np.asarray(grid.origin) + (np.array([x, y, z]) + 0.5 + 0.5 * n) * grid.cell
            bright = lit[g, z, y, x, :3].max() > 0
            if np.all(p > (-1, -1, 0)) and np.all(p < (1, 1, 2)) and np.dot(n, lamp - p) > 0:
                assert bright, (g, x, y, z)
                inside += 1
            elif np.any(p < (-1, -1, 0)) or np.any(p > (1, 1, 2)):
                assert not bright, (g, x, y, z)
                outside += 1
    assert inside >= 40 and outside >= 40


def test_a_list_too_small_is_made_again(monkeypatch):
    lit, where, counts, _, _ = _render(monkeypatch)
    small_lit, small_where, small_counts, _, _ = _render(monkeypatch, room=1)
    assert small_counts == [counts[0]] * 4  # each list counted past the room, then made in full
    assert np.array_equal(where < 0, small_where < 0)
    # the same light: the injection's float sums may differ in the last bit from run to run (vct/inject_raster.glsl)
    assert np.allclose(small_lit, lit, rtol=1e-5, atol=1e-7 * float(lit.max()))
