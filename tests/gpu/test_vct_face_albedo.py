# SPDX-License-Identifier: GPL-3.0-or-later
"""VCT keeps each voxel face's albedo apart from its light and from the voxel's mean (vct/inject.face_albedo,
vct/face_albedo.glsl): a face reflects with the albedo of the surfaces whose light leaves through it, and a material's
colour edit re-makes the albedo, not the voxels or the injected light (issue: "keep albedo and emission apart from
occupancy in the voxel data so a material edit never re-voxelizes").

The materials here are plain Lambert ones (no Principled layers), whose transport albedo is their base colour, so
each face's expected albedo is a colour of the scene. Stored as float16: within 2⁻¹¹ relative, 1e-3 absolute."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct import parts
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from bounce_gi.gpu_kernels.vct.trace import read_level
from support.lpv_transfer import rerun
from support.synthetic import open_room_with_block, quad, quad_scene

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))
FLOAT16 = 1e-3
WHITE, RUG, WALL = (0.8, 0.8, 0.8), (0.7, 0.1, 0.05), (0.1, 0.6, 0.2)
PX, MX, PY, MY, PZ, MZ = range(6)  # face directions +x, −x, +y, −y, +z, −z


def _albedo(engine) -> tuple:
    """vct_albedo's six face volumes as (nz, ny, nx, 4) arrays, and the grid."""
    pipe = engine.pipeline

    def grab(ctx):
        faces = pipe.cache.entries["vct_albedo"].value
        return [read_level(ctx, pipe.programs, t, faces.grid, 0) for t in faces.textures], faces.grid
    return engine.worker.call(grab)


def _voxel(grid, p) -> tuple:
    """(z, y, x) index of the voxel holding point p."""
    i = np.floor((np.asarray(p, np.float64) - np.asarray(grid.origin)) / grid.cell).astype(int)
    return int(i[2]), int(i[1]), int(i[0])


def test_each_face_reflects_its_own_surface():
    """A white floor, a red rug 1 mm above part of it and a green wall standing on the floor (which goes on
    behind it). The voxels the rug lies
    in reflect the rug upwards (+z) and the floor downwards (−z: the floor's underside, the rug's hidden behind it);
    the voxels where the wall meets the floor reflect green towards the room (−y) and white upwards. A voxel's mean
    albedo would give each of these faces a mix of the two surfaces."""
    z, y = 0.03, 0.97  # away from the voxel boundaries of this grid
    floor = quad([(-2, -2, z), (2, -2, z), (2, 1.5, z), (-2, 1.5, z)], (0, 0, 1))
    rug = quad([(-2, -2, z + 0.001), (0, -2, z + 0.001), (0, 0, z + 0.001), (-2, 0, z + 0.001)], (0, 0, 1))
    wall = quad([(-2, y, z), (2, y, z), (2, y, 2), (-2, y, 2)], (0, -1, 0))
    sun = Light("sun", "SUN", (1, 1, 1), 3.0, np.eye(4))
    scene = quad_scene([(floor, 0), (rug, 1), (wall, 2)],
                       [Material("white", WHITE), Material("rug", RUG), Material("wall", WALL)],
                       [sun], (0, -4, 3), (0, 0.5, 0.3), lens=20.0)
    engine = Engine()
    try:
        engine.render(scene, SETTINGS)
        faces, grid = _albedo(engine)
    finally:
        engine.shutdown()
    for x, w in ((-1.5, -1.5), (-1.0, -0.5), (-0.5, -1.2)):  # under the rug, away from its edges
        v = _voxel(grid, (x, w, z))
        assert np.allclose(faces[PZ][v][:3], RUG, atol=FLOAT16), (v, faces[PZ][v])
        assert np.allclose(faces[MZ][v][:3], WHITE, atol=FLOAT16), (v, faces[MZ][v])
    for x in (-1.0, 0.6, 1.5):  # the wall's foot, beside the rug and beyond it
        v = _voxel(grid, (x, y, z))
        assert np.allclose(faces[MY][v][:3], WALL, atol=FLOAT16), (v, faces[MY][v])
        if x > 0:
            assert np.allclose(faces[PZ][v][:3], WHITE, atol=FLOAT16), (v, faces[PZ][v])


@pytest.mark.parametrize("apart", [True, False], ids=["parts", "all lights at once"])
def test_a_colour_edit_keeps_the_voxels_and_the_light(monkeypatch, apart):
    """The block recoloured: only the faces' albedo, the sum of the parts and what follows them run again — not the
    voxelisation, the geometry's parts or any part's injection (the lamp's and the sky's, or, where the parts would
    not fit, the one of every light) — and the image is what a render from scratch of the recoloured room gives.
    Tolerance 1e-6 of the pass's largest value: both sum the same parts in the same order, what may differ is the
    order of the injection's compare-and-swap adds (measured 0 on llvmpipe)."""
    if not apart:
        monkeypatch.setattr(parts, "PART_BYTES_CAP", 0)
    injected = {"vct_inject_lamps", "vct_inject_sky"} if apart else {"vct_inject_all"}
    engine, fresh = Engine(), Engine()
    try:
        first = engine.render(open_room_with_block(), SETTINGS)
        assert injected <= set(rerun(first)), rerun(first)
        edited = engine.render(open_room_with_block(block=(0.9, 0.3, 0.1)), SETTINGS)
        ran = set(rerun(edited))
        assert {"vct_albedo", "vct_inject", "vct_bounce"} <= ran, ran
        assert not ran & ({"vct_voxelize", "vct_geometry"} | injected), ran
        cold = fresh.render(open_room_with_block(block=(0.9, 0.3, 0.1)), SETTINGS)
        for name in ("Diffuse Indirect", "Combined"):
            a, b = edited.passes[name], cold.passes[name]
            assert np.abs(a - b).max() <= 1e-6 * float(np.abs(b).max()), name
        before = engine.render(open_room_with_block(), SETTINGS)  # and back: the light kept
        assert not set(rerun(before)) & ({"vct_voxelize"} | injected)
    finally:
        engine.shutdown()
        fresh.shutdown()
