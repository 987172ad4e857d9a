# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.voxel.voxelize + common.grid (Freed 2018, §4.1): coverage against trimesh, exact areas, albedo weighting,
determinism, fixed-point overflow handling and lattice snapping. Runs on Mesa llvmpipe through EGL (~10 s)."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.direct import geometry as direct
from bounce_gi.gpu_kernels.voxel import tessellate as vt
from bounce_gi.gpu_kernels.voxel import voxelize as vz
from bounce_gi.gpu_kernels.common.grid import LATTICE_PHASE, Grid
from bounce_gi.gpu_kernels.scene import Material, Scene, Texture

trimesh = pytest.importorskip("trimesh")
MODES = ("raster", "tessellation")


def make_scene(positions, material_index=None, materials=None, uvs=None, textures=()):
    pos = np.asarray(positions, np.float32).reshape(-1, 3, 3)
    t = len(pos)
    n = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return Scene(pos, np.repeat(n[:, None], 3, axis=1).astype(np.float32),
                 np.zeros((t, 3, 2), np.float32) if uvs is None else np.asarray(uvs, np.float32).reshape(t, 3, 2),
                 np.zeros(t, np.int32) if material_index is None else np.asarray(material_index, np.int32),
                 materials or [Material("grey", (0.5, 0.5, 0.5))], list(textures))


def run(gl, scene, grid, mode, **kw):
    """Voxelise and read back: ({name: (nz, ny, nx, 4)}, VoxelVolumes)."""
    ctx, programs = gl
    geometry = direct.upload_geometry(ctx, programs, scene)
    textures = direct.upload_textures(ctx, scene)
    try:
        volumes = vz.voxelize(ctx, programs, scene, geometry, textures, grid, mode=mode, **kw)
        data = volumes.read()
        assert np.array_equal(volumes.occupancy(), data["area"][..., 3] > 0)
        volumes.release()
    finally:
        geometry.release()
        for t in textures:
            t.release()
    return data, volumes


def quad(corners):
    """Two triangles of the quad a-b-c-d (counter-clockwise)."""
    a, b, c, d = (np.asarray(x, np.float64) for x in corners)
    return np.array([[a, b, c], [a, c, d]])


# --------------------------------------------------------------------------- (a) coverage vs trimesh

def trimesh_occupancy(mesh, grid: Grid) -> np.ndarray:
    """trimesh's surface voxels mapped onto `grid`. trimesh's `voxelized(pitch)` (method 'subdivide') rounds the
    vertices of the mesh subdivided to edges ≤ pitch/2 to the nearest multiple of pitch, i.e. its voxel k is
    centred on k·pitch. Shifting the mesh by −(origin + cell/2) puts those centres on our cell centres, so
    trimesh index k is our voxel k."""
    shifted = mesh.copy()
    shifted.apply_translation(-(np.asarray(grid.origin) + 0.5 * grid.cell))
    idx = np.round(shifted.voxelized(grid.cell).points / grid.cell).astype(int)
    inside = np.all((idx >= 0) & (idx < grid.size), axis=1)
    occ = np.zeros(grid.shape_zyx, bool)
    occ[idx[inside, 2], idx[inside, 1], idx[inside, 0]] = True
    return occ


def _meshes():
    rot = trimesh.transformations.rotation_matrix(0.3, [1, 2, 3])
    # Offsets keep mesh vertices off voxel boundaries, where trimesh's round-half-to-even picks a side arbitrarily.
    box = trimesh.creation.box(extents=(1.7, 1.1, 0.6), transform=rot)
    thin = trimesh.Trimesh(vertices=[[0.013, 0.021, 0.007], [1.9, 1.3, 0.7], [1.9, 1.312, 0.718]], faces=[[0, 1, 2]])
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    sphere.apply_translation([0.0123, 0.0077, 0.0031])
    return {"icosphere": sphere, "box": box, "thin_triangle": thin}


MESHES = _meshes()
# Bounds, per mode. trimesh marks the voxels holding vertices of the mesh subdivided to edges ≤ pitch/2, a
# point sampling of the surface: every voxel it marks really contains surface, so the exact, conservative
# raster mode must include them all (recall 1 up to points landing exactly on a voxel face); the raster mode
# also marks voxels the surface only clips by a sliver, which sampling misses, so its IoU is lower (measured
# 0.90 sphere / 0.94 box / 0.88 thin, recall 1.0). The tessellation mode samples too (sub-triangle centroids,
# ≤ 1/2 voxel apart), so it agrees better but not voxel for voxel (measured IoU 0.945 / 0.963 / 0.906, recall
# ≥ 0.976). The bounds leave ~0.03–0.08 of slack for other drivers' rasteriser/tessellator rounding.
BOUNDS = {"raster": {"iou": 0.80, "recall": 0.999}, "tessellation": {"iou": 0.88, "recall": 0.95}}


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", sorted(MESHES))
def test_surface_voxels_match_trimesh(gl, mode, name):
    mesh = MESHES[name]
    scene = make_scene(mesh.triangles)
    grid = Grid.fit(*scene.bounds(), 64)
    ref = trimesh_occupancy(mesh, grid)
    data, _ = run(gl, scene, grid, mode)
    occ = data["area"][..., 3] > 0
    inter = np.count_nonzero(occ & ref)
    iou, recall = inter / np.count_nonzero(occ | ref), inter / np.count_nonzero(ref)
    print(f"{name} {mode}: ours {occ.sum()} trimesh {ref.sum()} IoU {iou:.4f} recall {recall:.4f}")
    assert iou >= BOUNDS[mode]["iou"] and recall >= BOUNDS[mode]["recall"], (iou, recall)


# --------------------------------------------------------------------------- (b) total area

@pytest.mark.parametrize("mode", MODES)
def test_total_area_equals_mesh_area(gl, mode):
    """Both modes compute exact areas (raster: clipped polygons; tessellation: sub-triangles tiling the patch).
    What remains is float32 geometry and 2^-24 cell² fixed-point rounding: 1e-4 relative (raster) is far
    inside the brief's 1 %, and 1e-4 (tessellation) is the brief's bound; measured ≤ 4e-7."""
    mesh = trimesh.util.concatenate([MESHES["icosphere"], MESHES["box"]])
    scene = make_scene(mesh.triangles)
    data, _ = run(gl, scene, Grid.fit(*scene.bounds(), 64), mode)
    assert data["area"][..., 3].sum(dtype=np.float64) == pytest.approx(mesh.area, rel=1e-4)
    # Projected areas: Σ A|n_axis| per axis over all voxels equals the same sum over the triangles.
    proj = (mesh.area_faces[:, None] * np.abs(mesh.face_normals)).sum(axis=0)
    assert data["area"][..., :3].sum(axis=(0, 1, 2), dtype=np.float64) == pytest.approx(proj, rel=1e-4)


# --------------------------------------------------------------------------- (c) a wall filling a voxel layer

@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_axis_aligned_wall_fills_its_layer(gl, mode, axis):
    """A unit square wall at the centre of layer 1 of a 4³ grid of 0.25 m cells covers the layer's 16 voxels."""
    grid = Grid((0.0, 0.0, 0.0), 0.25, (4, 4, 4))
    corners = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)
    pts = np.insert(corners, axis, 0.375, axis=1)
    data, _ = run(gl, make_scene(quad(pts)), grid, mode)
    area = np.moveaxis(data["area"], 2 - axis, 0)  # layer index first
    cell2 = 0.0625
    # Layer totals are exact in both modes (float32 + fixed point: 1e-6).
    assert area[1, ..., axis].sum() == pytest.approx(16 * cell2, rel=1e-6)
    assert np.abs(np.delete(area, 1, axis=0)).max() == 0.0  # nothing outside the layer
    others = [a for a in range(3) if a != axis]
    assert np.abs(area[..., others]).max() == 0.0  # no projected area on the other planes
    opacity = np.moveaxis(data["albedo"], 2 - axis, 0)[1, ..., 3]
    if mode == "raster":
        # Exact clipping: every voxel of the layer holds exactly one cell² (rel 1e-6 for float32 + fixed point).
        np.testing.assert_allclose(area[1, ..., axis], cell2, rtol=1e-6)
        np.testing.assert_allclose(area[1, ..., 3], cell2, rtol=1e-6)
        np.testing.assert_array_equal(opacity, 1.0)
    else:
        # Sub-triangles straddling a voxel face go whole to the voxel of their centroid, so a voxel gains or
        # loses part of the sub-triangles (≤ 1/2 voxel across) along its border: measured 0.963–1.037 cell².
        np.testing.assert_allclose(area[1, ..., axis], cell2, rtol=0.1)
        assert opacity.min() > 0.9 and opacity.max() == 1.0


# --------------------------------------------------------------------------- (d) albedo weighting

def test_albedo_emission_and_normal_are_area_weighted(gl):
    """Voxel (0,0,0) of a 2³ grid of 1 m cells holds a horizontal quad of material A (constant colour, metallic
    0.5, emissive; area 0.32) and a vertical quad of material B (2×1 texture: left half L, right half R; area
    0.36), whose colour boundary lies on a raster pixel boundary at supersample 2, so raster is exact."""
    ca, L, R = np.array([0.9, 0.2, 0.1]), np.array([0.1, 0.3, 0.9]), np.array([0.7, 0.7, 0.1])
    tex = Texture("lr", np.array([[[*L, 1.0], [*R, 1.0]]], np.float32), interpolation="Closest", extension="EXTEND")
    mats = [Material("A", tuple(ca), metallic=0.5, emission=(2.0, 1.0, 0.0)), Material("B", base_color_texture=0)]
    qa = quad([[0.1, 0.1, 0.25], [0.9, 0.1, 0.25], [0.9, 0.5, 0.25], [0.1, 0.5, 0.25]])   # normal +z, area 0.32
    qb = quad([[0.75, 0.2, 0.1], [0.75, 0.8, 0.1], [0.75, 0.8, 0.7], [0.75, 0.2, 0.7]])   # normal +x, area 0.36
    uv_b = quad([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])[..., :2]                       # u along y
    scene = make_scene(np.concatenate([qa, qb]), [0, 0, 1, 1], mats,
                       np.concatenate([np.zeros((2, 3, 2)), uv_b]), [tex])
    a1, a2 = 0.32, 0.36
    want_albedo = (a1 * ca * 0.5 + a2 * 0.5 * (L + R)) / (a1 + a2)
    want_emission = a1 * np.array([2.0, 1.0, 0.0]) / (a1 + a2)
    want_normal = np.array([a2, 0.0, a1]) / (a1 + a2)
    for mode, tol in (("raster", 1e-5), ("tessellation", 0.03)):
        # tessellation: sub-triangles (≤ 1/8 voxel at supersample 8) crossing the colour boundary take the
        # colour at their centroid, so the texture's share is approximate: 0.03 absolute.
        data, _ = run(gl, scene, Grid((0, 0, 0), 1.0, (2, 2, 2)), mode, supersample=2 if mode == "raster" else 8)
        np.testing.assert_allclose(data["area"][0, 0, 0], [a2, 0.0, a1, a1 + a2], rtol=1e-5)
        np.testing.assert_allclose(data["albedo"][0, 0, 0, :3], want_albedo, atol=tol)
        np.testing.assert_allclose(data["emission"][0, 0, 0, :3], want_emission, rtol=1e-5)
        np.testing.assert_allclose(data["normal"][0, 0, 0, :3], want_normal, rtol=1e-5)
        assert data["albedo"][0, 0, 0, 3] == pytest.approx(max(a1, a2), rel=1e-5)  # max projected area / cell²
        assert np.count_nonzero(data["area"][..., 3]) == 1


def test_sides_keep_the_colour_each_side_of_a_voxel_sees(gl):
    """sides=True: a white floor (z = 0.3) with a red rug 1 mm above its middle and a blue patch 1 mm below one
    corner, in 1/8 m voxels. Where the rug lies, the voxels' front (+z, the canonical normal's side) sees the rug
    alone and their back the floor; under the blue patch the front sees the floor and the back the patch; elsewhere
    both sides see the floor. Areas, normals and the one-albedo mean (sides=False) are unchanged. Exact up to the
    fixed point's rounding (1e-5)."""
    white, red, blue = np.array([0.8] * 3), np.array([0.7, 0.1, 0.05]), np.array([0.05, 0.2, 0.6])
    floor = quad([(0, 0, 0.3), (1, 0, 0.3), (1, 1, 0.3), (0, 1, 0.3)])
    rug = quad([(0.25, 0.25, 0.301), (0.75, 0.25, 0.301), (0.75, 0.75, 0.301), (0.25, 0.75, 0.301)])
    patch = quad([(0, 0, 0.299), (0.25, 0, 0.299), (0.25, 0.25, 0.299), (0, 0.25, 0.299)])
    mats = [Material("white", tuple(white)), Material("red", tuple(red)), Material("blue", tuple(blue))]
    scene = make_scene(np.concatenate([floor, rug, patch]), [0, 0, 1, 1, 2, 2], mats)
    grid = Grid((0, 0, 0), 0.125, (8, 8, 8))
    one, _ = run(gl, scene, grid, "raster")
    both, _ = run(gl, scene, grid, "raster", sides=True)
    k = 2  # the layer z in [0.25, 0.375)
    np.testing.assert_array_equal(both["area"], one["area"])
    np.testing.assert_array_equal(both["normal"], one["normal"])
    front, back = both["albedo"][k, ..., :3], both["albedo_back"][k, ..., :3]  # (y, x, 3)
    for (y, x), want_front, want_back in (((3, 3), red, white), ((1, 1), white, blue), ((1, 6), white, white)):
        np.testing.assert_allclose(front[y, x], want_front, atol=1e-5)
        np.testing.assert_allclose(back[y, x], want_back, atol=1e-5)
    np.testing.assert_allclose(one["albedo"][k, 3, 3, :3], (red + white) / 2, atol=1e-5)  # equal areas, mixed
    assert "albedo_back" not in one


# --------------------------------------------------------------------------- (e) determinism

@pytest.mark.parametrize("mode", MODES)
def test_two_runs_are_bit_identical(gl, mode):
    """Integer atomics commute, so many fragments racing into the same voxels (a 1280-triangle textured sphere
    in an 8³ grid) still give identical bytes; float atomics or last-writer-wins would not."""
    mesh = MESHES["icosphere"]
    rng = np.random.default_rng(1)
    tex = Texture("noise", rng.random((16, 16, 4)).astype(np.float32))
    uvs = rng.random((len(mesh.faces), 3, 2))
    scene = make_scene(mesh.triangles, np.arange(len(mesh.faces)) % 2,
                       [Material("t", base_color_texture=0), Material("c", (0.3, 0.6, 0.2), emission=(1, 2, 3))],
                       uvs, [tex])
    grid = Grid.fit(*scene.bounds(), 8)
    first, _ = run(gl, scene, grid, mode)
    second, _ = run(gl, scene, grid, mode)
    for name in vz.VOLUME_NAMES:
        assert first[name].tobytes() == second[name].tobytes(), name


# --------------------------------------------------------------------------- exact per-voxel areas (raster)

def clip_area_cpu(tri: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Area of triangle ∩ box by Sutherland–Hodgman clipping against the six faces (float64)."""
    poly = [np.asarray(p, np.float64) for p in tri]
    for axis in range(3):
        for bound, sign in ((lo[axis], 1.0), (hi[axis], -1.0)):
            out = []
            for i, a in enumerate(poly):
                b = poly[(i + 1) % len(poly)]
                fa, fb = sign * (a[axis] - bound), sign * (b[axis] - bound)
                if fa >= 0:
                    out.append(a)
                if (fa >= 0) != (fb >= 0):
                    out.append(a + (b - a) * (fa / (fa - fb)))
            poly = out
            if len(poly) < 3:
                return 0.0
    p = np.array(poly)
    return 0.5 * np.linalg.norm(np.cross(p[1:-1] - p[0], p[2:] - p[0]).sum(axis=0))


def test_raster_areas_are_exact_per_voxel(gl):
    """Random triangles (some leaving the grid) against a float64 CPU clipper: every voxel's area and its three
    projected areas. Tolerance 1e-5 cell² per voxel: float32 pixel coordinates (~1e-6 cell) times the few
    pieces per voxel, plus < 2^-18 = 3.8e-6 cell² per sliver piece from the minimum-count rule
    (voxel/common.glsl); a wrong clip, slab or axis mapping errs by a sizeable fraction of a cell²."""
    rng = np.random.default_rng(7)
    centres = rng.uniform(-0.5, 8.5, (40, 1, 3))
    tris = centres + rng.normal(0.0, 1.5, (40, 3, 3))
    grid = Grid((0.0, 0.0, 0.0), 1.0, (8, 8, 8))
    data, _ = run(gl, make_scene(tris), grid, "raster")
    want = np.zeros((8, 8, 8, 4))
    for tri in tris:
        n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        n = np.abs(n) / np.linalg.norm(n)
        lo = np.clip(np.floor(tri.min(axis=0)).astype(int), 0, 8)
        hi = np.clip(np.floor(tri.max(axis=0)).astype(int) + 1, 0, 8)
        for k in range(lo[2], hi[2]):
            for j in range(lo[1], hi[1]):
                for i in range(lo[0], hi[0]):
                    a = clip_area_cpu(tri, np.array([i, j, k]), np.array([i + 1, j + 1, k + 1]))
                    want[k, j, i] += [a * n[0], a * n[1], a * n[2], a]
    np.testing.assert_allclose(data["area"], want, atol=1e-5)
    occ = data["area"][..., 3] > 0
    assert np.all(occ[want[..., 3] > 1e-7]) and not np.any(occ[want[..., 3] == 0.0])  # conservative, no extras


# --------------------------------------------------------------------------- fixed-point overflow

@pytest.mark.parametrize("mode", MODES)
def test_fixed_point_overflow_is_detected_and_rerun(gl, mode):
    """With 31 fixed-point bits a voxel holds < 2 cell²; six stacked unit quads put 3 cell² in every voxel.
    The wrapped sum must be detected and the pass re-run with fewer bits, matching the default run."""
    layers = [quad([[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]]) for z in np.linspace(0.1, 0.9, 6)]
    scene = make_scene(np.concatenate(layers))
    grid = Grid((0.0, 0.0, 0.0), 0.5, (2, 2, 2))
    ref, ref_vol = run(gl, scene, grid, mode)
    got, vol = run(gl, scene, grid, mode, scale_bits=31)
    assert ref_vol.reruns == 0 and vol.reruns >= 1 and vol.scale_bits < 31
    np.testing.assert_allclose(got["area"], ref["area"], rtol=1e-5, atol=1e-6)
    assert got["area"][..., 3].sum() == pytest.approx(6.0, rel=1e-5)


# --------------------------------------------------------------------------- CPU split for tessellation

def test_split_for_tessellation_bounds_levels_and_keeps_area():
    tri = np.array([[[0, 0, 0], [300, 0, 0], [0, 170, 0]], [[0, 0, 0], [1, 0, 0], [0, 1, 1]]], np.float64)
    src, bary = vt.split_for_tessellation(tri, cell=1.0, supersample=2)
    pieces = np.einsum("scw,swd->scd", bary, tri[src])
    assert vt.tessellation_levels(pieces, 1.0, 2).max() <= vt.MAX_TESS_LEVEL
    longest = np.linalg.norm(pieces[:, [1, 2, 0]] - pieces, axis=2).max(axis=1)
    assert longest.max() * 2 <= vt.MAX_TESS_LEVEL  # every piece within the hardware's level
    assert np.count_nonzero(src == 1) == 1  # a small triangle is left alone
    area = 0.5 * np.linalg.norm(np.cross(pieces[:, 1] - pieces[:, 0], pieces[:, 2] - pieces[:, 0]), axis=1)
    assert area[src == 0].sum() == pytest.approx(0.5 * 300 * 170, rel=1e-12)
    n = np.cross(pieces[:, 1] - pieces[:, 0], pieces[:, 2] - pieces[:, 0])
    assert np.all(n[src == 0, 2] > 0)  # orientation preserved


def test_unknown_mode_is_rejected(gl):
    with pytest.raises(ValueError, match="mode"):
        run(gl, make_scene(quad([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])), Grid((0, 0, 0), 1, (2, 2, 2)), "magic")


# --------------------------------------------------------------------------- (f) lattice snapping

def test_grid_fit_snaps_origin_to_the_lattice():
    rng = np.random.default_rng(3)
    lo, hi = np.array([-1.3, 0.2, -4.7]), np.array([2.1, 1.9, -1.1])
    base = Grid.fit(lo, hi, 64)
    assert max(base.size) >= 63 and all(n <= 64 for n in base.size)  # 63 when the rounded-up cell lets it fit
    for _ in range(50):
        shift = rng.uniform(-1, 1, 3) * base.cell * 0.999   # less than one cell
        g = Grid.fit(lo + shift, hi + shift, 64)
        assert g.cell == base.cell  # the cell depends on the extent only
        ratio = np.asarray(g.origin) / g.cell - LATTICE_PHASE
        np.testing.assert_allclose(ratio, np.round(ratio), rtol=0, atol=1e-9)  # origin on the lattice
        # ... and the lattice itself did not move: the two origins differ by whole cells.
        steps = (np.asarray(g.origin) - np.asarray(base.origin)) / base.cell
        np.testing.assert_allclose(steps, np.round(steps), rtol=0, atol=1e-9)
        glo, ghi = g.bounds()
        assert np.all(glo + g.cell <= lo + shift + 1e-12) and np.all(ghi - g.cell >= hi + shift - 1e-12)  # margins


def test_grid_centered_and_queries():
    g = Grid.centered((0.37, -2.0, 5.05), 0.1, (5, 4, 5))
    ratio = np.asarray(g.origin) / g.cell
    np.testing.assert_allclose(ratio, np.round(ratio), atol=1e-9)
    assert tuple(g.voxel_index((0.37, -2.0, 5.05))) == (2, 2, 2)  # odd sizes: the centre is in the middle voxel
    np.testing.assert_allclose(g.world_to_grid(g.cell_center(1, 2, 3)), [1.5, 2.5, 3.5])
    lo, hi = g.bounds()
    np.testing.assert_allclose(hi - lo, [0.5, 0.4, 0.5])
    assert g.shape_zyx == (5, 4, 5)


def test_a_floor_at_zero_lies_inside_a_voxel_at_every_scale():
    """A surface at a round coordinate (a floor at z = 0) must not sit on a voxel boundary of the grid or of the
    half-size and double-size lattices, where float rounding decides the voxel it falls into (it did, and a room
    scaled by 10⁴ came out 4% different with the LPV)."""
    for scale in (1e-3, 0.1, 1.0, 100.0, 1e4):
        g = Grid.fit(np.array([-1.0, -1.0, 0.0]) * scale, np.array([1.0, 1.0, 2.0]) * scale, 8)
        for cell in (g.cell / 2, g.cell, g.cell * 2):
            f = (0.0 - g.origin[2]) / cell % 1.0
            assert 0.1 < f < 0.9, (scale, cell, f)


# --------------------------------------------------------------------------- where surfaces lie, by axis

def test_positions_give_each_voxels_surfaces_centroid_and_box_and_axis_only_keeps_one_axis(gl):
    """positions=True: a floor at z = 0.3 cells into its voxels and a wall at x = 0.7 cells into its own, cut by the
    grid: every voxel's centroid and box (voxel fractions) are the pieces' own, exactly (the clipped polygons'
    centroids and corners; float32 rounding, 1e-5). axis_only keeps only the triangles of that dominant axis: the
    floor alone with 2 (z), the wall alone with 0 (x), and the two add up to all of them."""
    grid = Grid((0.0, 0.0, 0.0), 1.0, (4, 4, 4))
    floor = quad([(0.5, 0.5, 1.3), (3.5, 0.5, 1.3), (3.5, 3.5, 1.3), (0.5, 3.5, 1.3)])
    wall = quad([(2.7, 0.5, 0.5), (2.7, 3.5, 0.5), (2.7, 3.5, 3.5), (2.7, 0.5, 3.5)])
    scene = make_scene(np.concatenate([floor, wall]))
    both, _ = run(gl, scene, grid, "raster", positions=True)
    z_only, _ = run(gl, scene, grid, "raster", positions=True, axis_only=2)
    x_only, _ = run(gl, scene, grid, "raster", positions=True, axis_only=0)
    np.testing.assert_allclose(z_only["area"] + x_only["area"], both["area"], rtol=1e-6, atol=1e-9)
    for data, axis, at in ((z_only, 2, 0.3), (x_only, 0, 0.7)):
        has = data["area"][..., 3] > 0
        assert has.sum() == 16  # the quad crosses 4 × 4 voxels
        occupied = np.argwhere(has)  # (z, y, x)
        assert (occupied[:, 2 - axis] == (1 if axis == 2 else 2)).all()  # the floor in z-layer 1, the wall in x-layer 2
        np.testing.assert_allclose(data["position"][has][:, axis], at, atol=1e-5)
        np.testing.assert_allclose(data["extent_lo"][has][:, axis], at, atol=1e-5)
        np.testing.assert_allclose(data["extent_hi"][has][:, axis], at, atol=1e-5)
        # in the plane: the quad spans 0.5 … 3.5, so the edge voxels hold half of themselves, the others all
        for i in (a for a in range(3) if a != axis):
            index = occupied[:, 2 - i]
            lo = np.where(index == 0, 0.5, 0.0)
            hi = np.where(index == 3, 0.5, 1.0)
            np.testing.assert_allclose(data["extent_lo"][has][:, i], lo, atol=1e-5)
            np.testing.assert_allclose(data["extent_hi"][has][:, i], hi, atol=1e-5)
            np.testing.assert_allclose(data["position"][has][:, i], (lo + hi) / 2, atol=1e-5)


def test_positions_keep_which_way_the_surfaces_face(gl):
    """positions=True: normal w is the area-weighted facing, +1 where every piece faces along the voxel's canonical
    normal (a floor facing up), −1 where every piece faces the other way (a ceiling facing down: the canonical normal
    forgets it) and 0 where as much faces each way (a slab's two faces in one voxel) — what lpv/wall_sides.py reads
    to know which side of a wall is its front. Fixed-point sums: exact to 1e-6."""
    grid = Grid((0.0, 0.0, 0.0), 1.0, (4, 4, 4))
    up = quad([(0.5, 0.5, 0.3), (3.5, 0.5, 0.3), (3.5, 3.5, 0.3), (0.5, 3.5, 0.3)])
    down = quad([(0.5, 0.5, 1.5), (0.5, 3.5, 1.5), (3.5, 3.5, 1.5), (3.5, 0.5, 1.5)])
    slab = np.concatenate([quad([(0.5, 0.5, 2.2), (3.5, 0.5, 2.2), (3.5, 3.5, 2.2), (0.5, 3.5, 2.2)]),
                           quad([(0.5, 0.5, 2.8), (0.5, 3.5, 2.8), (3.5, 3.5, 2.8), (3.5, 0.5, 2.8)])])
    data, _ = run(gl, make_scene(np.concatenate([up, down, slab])), grid, "raster", positions=True, axis_only=2)
    has = data["area"][..., 3] > 0
    for layer, facing in ((0, 1.0), (1, -1.0), (2, 0.0)):
        np.testing.assert_allclose(data["normal"][layer][has[layer]][:, 2], 1.0, atol=1e-6)  # canonical: +z always
        np.testing.assert_allclose(data["normal"][layer][has[layer]][:, 3], facing, atol=1e-6)
