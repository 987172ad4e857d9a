# SPDX-License-Identifier: GPL-3.0-or-later
"""voxel/voxelize.py `region` and lpv/regional.py: an object's move voxelises again only the part of the grid it
left and entered, and that part is the whole grid's voxelisation voxel for voxel (llvmpipe, EGL)."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.common.grid import Grid
from bounce_gi.gpu_kernels.direct import geometry as direct
from bounce_gi.gpu_kernels.lpv import regional
from bounce_gi.gpu_kernels.scene import Material, Scene, Texture
from bounce_gi.gpu_kernels.voxel import voxelize as vz

trimesh = pytest.importorskip("trimesh")
NAMES = ("area", "albedo", "normal", "emission", "albedo_back", "position", "extent_lo", "extent_hi")


def _scene(shift=(0.0, 0.0, 0.0)):
    """A textured sphere (1280 triangles) on a floor that runs out of the grid, beside a two-sided plate; the sphere
    moved by `shift`."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.8)
    tris = [np.asarray(sphere.triangles) + np.asarray((0.2, 0.1, 1.0)) + np.asarray(shift)]
    floor = np.array([[(-3, -3, 0.05), (3, -3, 0.05), (3, 3, 0.05)], [(-3, -3, 0.05), (3, 3, 0.05), (-3, 3, 0.05)]])
    plate = np.array([[(1.3, -1, 0.3), (1.3, 1, 0.3), (1.3, 1, 1.6)], [(1.3, -1, 0.3), (1.3, 1, 1.6), (1.3, -1, 1.6)]])
    pos = np.concatenate(tris + [floor, plate]).astype(np.float32)
    n = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    rng = np.random.default_rng(3)
    mats = [Material("tex", base_color_texture=0), Material("red", (0.8, 0.1, 0.1), emission=(0.5, 0.2, 0.1)),
            Material("white", (0.9, 0.9, 0.9))]
    index = np.r_[np.arange(len(tris[0])) % 2, [2, 2, 1, 1]].astype(np.int32)
    return Scene(pos, np.repeat(n[:, None], 3, axis=1).astype(np.float32),
                 rng.random((len(pos), 3, 2)).astype(np.float32), index, mats,
                 [Texture("noise", rng.random((16, 16, 4)).astype(np.float32))])


GRID = Grid((-2.0, -2.0, -0.5), 0.125, (34, 33, 26))  # no power of two, as the LPV's fine grids (2n + 2)


def _voxelise(gl, scene, **kw):
    ctx, programs = gl
    geometry, textures = direct.upload_geometry(ctx, programs, scene), direct.upload_textures(ctx, scene)
    try:
        volumes = vz.voxelize(ctx, programs, scene, geometry, textures, GRID, sides=True, positions=True, **kw)
        data = volumes.read()
        volumes.release()
    finally:
        geometry.release()
        for t in textures:
            t.release()
    return data, volumes.grid


@pytest.mark.parametrize("region", [((8, 9, 10), (20, 22, 19)),   # inside, through the sphere and the floor
                                    ((0, 0, 0), (34, 5, 26)),     # along the grid's faces, the floor leaving it
                                    ((26, 3, 6), (27, 30, 16))])  # one voxel thick, through the plate
@pytest.mark.parametrize("axis", [-1, 0, 2])
def test_a_regions_voxels_are_the_whole_grids(gl, region, axis):
    """Every volume of a region's voxelisation (sides, positions, each axis alone or all) equals the whole grid's
    in those voxels, byte for byte: the same triangles cross them, clipped in the whole grid's coordinates, and
    the integer sums commute."""
    whole, _ = _voxelise(gl, _scene(), axis_only=axis)
    part, grid = _voxelise(gl, _scene(), axis_only=axis, region=region)
    (x0, y0, z0), (x1, y1, z1) = region
    assert grid.size == (x1 - x0, y1 - y0, z1 - z0)
    assert grid.origin == pytest.approx(tuple(np.asarray(GRID.origin) + np.asarray(region[0]) * GRID.cell))
    assert axis >= 0 or (part["area"][..., 3] > 0).sum() > 0  # all axes: each region crosses surfaces
    for name in NAMES:
        assert np.array_equal(part[name], whole[name][z0:z1, y0:y1, x0:x1]), name


def test_a_moved_objects_region_updates_a_kept_voxelisation_to_the_new_one(gl):
    """The sphere moved 0.3 m: moved_region spans its voxels before and after (grown by one), far less than the
    grid, and the kept voxelisation with that region pasted in is the new scene's own, byte for byte. Another
    material state, or nothing moved, asks for the whole grid."""
    before, after = _scene(), _scene((0.3, 0.0, 0.1))
    names = ("area", "normal", "albedo", "albedo_back", "position", "extent_lo", "extent_hi")
    old = [{k: v for k, v in _voxelise(gl, before, axis_only=a)[0].items() if k in names} for a in range(3)]
    kept = regional.keep(old, before, regional.inputs_key(before, "m"))
    region = regional.moved_region(kept, after, GRID, regional.inputs_key(after, "m"))
    lo, hi = region
    assert np.prod(hi - lo) < 0.25 * np.prod(GRID.size)
    part = [_voxelise(gl, after, axis_only=a, region=region)[0] for a in range(3)]
    updated = regional.paste(kept.arrays(), region, part)
    new = [_voxelise(gl, after, axis_only=a)[0] for a in range(3)]
    for a in range(3):
        for name in names:
            assert np.array_equal(updated[a][name], new[a][name]), (a, name)
    assert regional.moved_region(kept, after, GRID, regional.inputs_key(after, "other materials")) is None
    assert regional.moved_region(kept, before, GRID, regional.inputs_key(before, "m")) is None


def test_a_region_outside_the_grid_is_refused(gl):
    with pytest.raises(ValueError, match="not a part of grid"):
        vz.region_grid(GRID, ((0, 0, 0), (35, 4, 4)))
