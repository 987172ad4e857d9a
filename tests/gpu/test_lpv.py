# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV properties that must hold exactly or by construction (issue: Light Propagation Volumes).

- Propagation conserves flux in empty space: far face 0.4006696846 sr + 4 side faces 0.4234313544 sr = 2π/3 per
  neighbour, and the band-1 terms cancel over the 30 face directions, so one step moves exactly the flux it was
  given while no light reaches the border. Tolerance 0.1% (the issue's bound; float32 sums of 32³ cells).
- Negative lobes propagate unclamped by default; clamping them adds energy (measured and asserted > 1).
- Light leaves through the open borders and is never created: the flux in the grid never exceeds the start.
- Injection scales with texel area, so doubling the RSM resolution changes the injected flux only by sampling.
"""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.lpv.propagate import step_fluxes
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.common.grid import Grid
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.gl.programs import ProgramCache
from bounce_gi.gpu_kernels.scene import Camera, Light, Material, Scene, World
from bounce_gi.gpu_kernels.common import camera as cam
from support.synthetic import sphere_scene

CLAMPED_COSINE = lambda n: np.array([0.886226925, -1.023326708 * n[1], 1.023326708 * n[2], -1.023326708 * n[0]])


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _point_vpl(grid, flux, normal):
    """One Lambertian VPL of `flux` (W, per channel) in the centre cell."""
    data = np.zeros(grid.shape_zyx + (3, 4), np.float32)
    c = tuple(n // 2 for n in grid.shape_zyx)
    data[c] = np.outer(np.ones(3), CLAMPED_COSINE(np.asarray(normal, float)) * flux / math.pi)
    return data


def _steps(engine, grid, initial, steps, **kw):
    settings = LpvSettings(occlusion=False, **kw)
    return engine.worker.call(lambda ctx: step_fluxes(ctx, ProgramCache(ctx), grid, initial, steps, settings))


def test_flux_is_conserved_per_step_in_empty_space(engine):
    grid = Grid((0.0, 0.0, 0.0), 1.0, (33, 33, 33))
    initial = _point_vpl(grid, 10.0, (0.3, -0.5, 0.81))
    fluxes = _steps(engine, grid, initial, 12)  # light is 12 cells from the centre: still 4 cells from the border
    for step, f in enumerate(fluxes, 1):
        assert np.allclose(f, 10.0, rtol=1e-3), (step, f)


def test_clamping_negative_lobes_adds_energy(engine):
    grid = Grid((0.0, 0.0, 0.0), 1.0, (33, 33, 33))
    initial = _point_vpl(grid, 10.0, (0.0, 0.0, 1.0))
    clamped = _steps(engine, grid, initial, 4, clamp_negative=True)
    growth = [f[0] / 10.0 for f in clamped]
    print("flux after each clamped step / injected:", [round(g, 3) for g in growth])
    assert growth[0] > 1.01 and growth[-1] > growth[0]  # clamping creates light; the default does not


def test_light_leaves_through_open_borders_and_is_never_created(engine):
    grid = Grid((0.0, 0.0, 0.0), 1.0, (9, 9, 9))
    initial = _point_vpl(grid, 5.0, (1.0, 0.0, 0.0))
    fluxes = np.array([f[0] for f in _steps(engine, grid, initial, 120)])
    assert np.all(fluxes <= 5.0 * (1 + 1e-4))  # float32 rounding only
    # The 2-band scheme is diffusive, so light lingers: measured 15% left after 40 steps, 1.1% after 80, 0.08%
    # after 120 in a 9³ grid. Bound: under 1% after 120 steps.
    assert fluxes[-1] < 0.01 * 5.0


def test_injection_does_not_depend_on_rsm_resolution(engine):
    scene = sphere_scene()
    injected = []
    for res in (64, 128):
        r = engine.render(scene, RenderSettings("lpv", 64, 48, lpv=LpvSettings(rsm_resolution=res, bounces=1,
                                                                                  max_iterations=8)))
        injected.append(r.info["cascades"][0]["injected_flux"])
    # Exact total: every ray of the bulb hits the sphere, so reflected flux = albedo × power per channel.
    expected = 0.5 * 100.0 * 3
    print("injected flux at RSM 64 / 128:", injected, "expected", expected)
    # Measured 0.99988 of it since each cube face counts only its own texels (1.03 before: the faces' overlap);
    # 0.5%, the bound of test_the_rsm_injects_exactly_the_flux_that_lands_in_a_closed_room.
    assert injected[0] == pytest.approx(expected, rel=0.005)
    assert injected[1] == pytest.approx(injected[0], rel=0.01)


@pytest.mark.parametrize("kind", ["POINT", "AREA"])
def test_the_rsm_injects_exactly_the_flux_that_lands_in_a_closed_room(engine, kind):
    """A closed room of albedo 1 (support/stress.box_room, a block inside) takes all of a light's power: the RSM's
    flux (reflected, so equal to the incident) sums to P per channel. Point and area lights are seen through shadow
    cubes whose faces are a few texels wider than 90°; each texel keeps only its share inside its own face
    (lpv/inject.glsl cube_share). Before that the overlap counted twice: 1.017 P (point) and 1.035 P (area).
    Measured since: 0.9997 and 0.9960 (the area light's per-sample shares, direct/eval.glsl's weights, are an
    approximation); bound 0.5%."""
    from support.stress import box_room

    scene = box_room(kind=kind, power=100.0, albedo=1.0, block_albedo=(1.0, 1.0, 1.0))
    r = engine.render(scene, RenderSettings("lpv", 32, 24, lpv=LpvSettings(resolution=16, rsm_resolution=32,
                                                                              bounces=1)))
    flux = r.info["cascades"][0]["injected_flux"]
    print(f"{kind}: injected {flux / 300.0:.4f} of the power")
    assert flux == pytest.approx(300.0, rel=0.005)


def test_transfer_matrices_match_the_face_loop(engine):
    """The precomputed linear maps (default path) and the explicit five-face loop (clamped path, on inputs with no
    negative face flux) give the same step."""
    grid = Grid((0.0, 0.0, 0.0), 1.0, (17, 17, 17))
    data = np.zeros(grid.shape_zyx + (3, 4), np.float32)
    data[8, 8, 8] = np.outer(np.ones(3), np.array([1.0, 0.0, 0.0, 0.0]))  # isotropic: every face flux > 0
    a = _steps(engine, grid, data, 3)
    b = _steps(engine, grid, data, 3, clamp_negative=True)
    assert np.allclose(a, b, rtol=1e-5)


@pytest.mark.parametrize("transport", ["transfer", "gather", "propagate"])
def test_closed_sphere_one_bounce_against_the_analytic_irradiance(engine, transport):
    """Inside a closed sphere of albedo ρ with a point light of flux Φ at its centre, the one-bounce indirect
    irradiance is uniform, E₁ = ρΦ/(4πR²) (every pair of points on a sphere has the same form factor).

    The issue's target is the mean within 15% of E₁. The gathered transport (default) meets it: measured at 32³
    1.005·E₁, spread 0.946–1.030; bound ±15% and no pixel beyond ±10% of the mean (the sphere is uniform; what
    spread there is comes from the VPL clusters and the voxels' centres). The propagating transport does not:
    64 iterations 0.71·E₁, spread 0.43–0.82 (256 iterations: 0.81·E₁) — light still in flight when iterations stop
    and light leaking through the fuzzy walls (17% absorbed on the outside at 256 iterations); it is held to
    today's level (0.65–1.15; spread within 0.45–1.5 of the mean: 0.49–1.57 measured since the lattice's boundaries
    moved to (k + 1/3) cells, common/grid.LATTICE_PHASE, 0.53–1.47 before) as a regression bound.
    """
    scene = sphere_scene(subdivisions=4)
    r = engine.render(scene, RenderSettings("lpv", 96, 72, lpv=LpvSettings(resolution=32, bounces=1,
                                                                              transport=transport)))
    e1 = 0.5 * 100.0 / (4 * math.pi)
    irradiance = r.passes["Diffuse Indirect"][..., 0] * math.pi
    ratio = irradiance.mean() / e1
    print(f"sphere ({transport}): mean E/E1 {ratio:.3f}, min {irradiance.min() / e1:.3f}, "
          f"max {irradiance.max() / e1:.3f}")
    if transport != "propagate":  # the transfer is the gather from fixed clusters: the same claim
        assert ratio == pytest.approx(1.0, abs=0.15)
        assert irradiance.min() > 0.9 * irradiance.mean() and irradiance.max() < 1.1 * irradiance.mean()
    else:
        assert 0.65 <= ratio <= 1.15
        assert irradiance.min() > 0.45 * irradiance.mean() and irradiance.max() < 1.6 * irradiance.mean()


def test_cascades_agree_with_a_single_grid_where_they_overlap(engine):
    """Three nested cascades (finest around the camera) against one grid: the finest cascade has half the cells
    of the coarse one, so the two estimates differ by discretisation only. The camera sits 0.3 m from the wall it
    looks at, so the finer cascades (centred on it) cover what it sees. Bound: means within 35% of each other
    (measured: see the printout), both light every pixel, and the 3-cascade image is not the 1-cascade one."""
    scene = sphere_scene(subdivisions=4, eye=(0.7, 0.0, 0.0))
    images = []
    means = []
    for cascades in (1, 3):
        r = engine.render(scene, RenderSettings("lpv", 64, 48, lpv=LpvSettings(resolution=16, cascades=cascades,
                                                                                  bounces=1)))
        di = r.passes["Diffuse Indirect"][..., 0]
        assert len(r.info["cascades"]) == cascades
        assert (di > 0).all()
        means.append(float(di.mean()))
        images.append(di)
    print("mean Diffuse Indirect, 1 vs 3 cascades:", means)
    assert means[1] == pytest.approx(means[0], rel=0.35)
    assert np.abs(images[1] - images[0]).max() > 1e-3 * means[0]


def test_world_light_is_direct_on_an_open_floor_and_absent_inside_a_closed_sphere(engine):
    """The world is a light (common/lights.py: the sky light). A white world of radiance 1 over an open floor: its
    Diffuse Direct is 1 (E = π, Cycles' DiffDir under a full sky), exactly up to float32, since every one of the sky's
    upward directions is unshadowed and the visibility is their weighted share; no other surface, so no indirect
    light. Inside a closed sphere the shadow maps of the sphere's own triangles keep every direction out: Diffuse
    Direct exactly 0. Its sky-lit outside injects VPLs that the 16³ volume's fuzzy walls let in a little: mean
    Diffuse Indirect measured 0.0008, bound 0.01 — the world's border injection, which this replaces, left 0.14
    here, and a leak of that order fails."""
    floor = np.array([[(-2, -2, 0), (2, -2, 0), (2, 2, 0)], [(-2, -2, 0), (2, 2, 0), (-2, 2, 0)]], np.float32)
    normals = np.tile(np.array([0, 0, 1], np.float32), (2, 3, 1))
    eye = (0.0, -3.0, 2.0)
    cam_to_world = np.linalg.inv(cam.look_at(eye, (0, 0, 0), (0, 0, 1)))
    open_scene = Scene(floor, normals, np.zeros((2, 3, 2), np.float32), np.zeros(2, np.int32),
                       [Material("floor", (0.5, 0.5, 0.5))], [], [], World((1.0, 1.0, 1.0)), Camera(cam_to_world))
    r = engine.render(open_scene, RenderSettings("lpv", 64, 48, lpv=LpvSettings(resolution=16, bounces=1)))
    hit = r.passes["Depth"][..., 0] < 1e9
    direct = r.passes["Diffuse Direct"][..., 0][hit]
    print("open floor under a white sky: Diffuse Direct", direct.min(), direct.max())
    np.testing.assert_allclose(direct, 1.0, atol=1e-5)
    assert r.passes["Diffuse Indirect"][hit].max() < 1e-6

    sphere = sphere_scene(subdivisions=3)
    sphere.lights = []
    sphere.world = World((1.0, 1.0, 1.0))
    sphere.materials[0].emission = (0.0, 0.0, 0.0)
    r = engine.render(sphere, RenderSettings("lpv", 64, 48, lpv=LpvSettings(resolution=16, bounces=1)))
    direct, indirect = r.passes["Diffuse Direct"][..., 0], r.passes["Diffuse Indirect"][..., 0]
    print("inside a closed sphere: max Diffuse Direct", direct.max(), "mean Diffuse Indirect", indirect.mean())
    assert direct.max() == 0.0
    assert indirect.mean() < 0.01


def test_a_suns_rsm_at_the_voxels_resolution_injects_its_flux(engine):
    """A sun's RSM needs no finer texels than two per LPV cell (lpv/passes.RSM_TEXELS_PER_CELL): its texels' flux
    is binned into surface voxels half a cell wide. A 20 m floor of albedo 0.5 under a 3 W/m² sun straight down
    reflects 0.5 × 3 × 400 = 600 W per channel. At 16³ the sun's map (the scene's bounding sphere, 28.8 m across)
    drops from 256 to 48 texels a side. Each texel carries its area's flux exactly; only where the floor's edge
    crosses a texel is the whole texel counted or none (its centre decides), so the total is exact up to half a
    texel along the 80 m perimeter: bound 80 × texel / 2 / 400 m² (6.0%). Measured 1.044 (1.0056 at 256 texels);
    a texel area out of step with the map's resolution would be off by its square."""
    from bounce_gi.gpu_kernels.lpv import passes
    from bounce_gi.gpu_kernels.lpv.rsm import view_resolution

    floor = np.array([[(-10, -10, 0), (10, -10, 0), (10, 10, 0)], [(-10, -10, 0), (10, 10, 0), (-10, 10, 0)]],
                     np.float32)
    normals = np.tile(np.array([0, 0, 1], np.float32), (2, 3, 1))
    cam_to_world = np.linalg.inv(cam.look_at((0.0, -14.0, 9.0), (0, 0, 0), (0, 0, 1)))
    sun = Light("sun", "SUN", (1, 1, 1), 3.0, np.eye(4))
    scene = Scene(floor, normals, np.zeros((2, 3, 2), np.float32), np.zeros(2, np.int32),
                  [Material("floor", (0.5, 0.5, 0.5))], [], [sun], World((0.0, 0.0, 0.0)), Camera(cam_to_world))
    # The propagating transport injects every texel (the transfer's would leave: nothing lies above the floor).
    r = engine.render(scene, RenderSettings("lpv", 64, 48, lpv=LpvSettings(resolution=16, bounces=1,
                                                                          transport="propagate")))
    flux = r.info["cascades"][0]["injected_flux"]
    width = 2 * 1.02 * math.hypot(10.0, 10.0)  # common/lights.ortho_view: the bounding sphere's radius × 1.02
    side = view_resolution(128, True, 1, width, (20.0 / 16) / passes.RSM_TEXELS_PER_CELL)
    bound = 80.0 * (width / side) / 2 / 400.0
    print(f"sun RSM {side} texels a side (uncapped 256); injected {flux / 1800:.4f} of 0.5 x 3 x 400 x 3; "
          f"bound {bound:.3f}")
    assert side < 256
    assert flux == pytest.approx(1800.0, rel=bound)


@pytest.mark.parametrize("downsample", [2, 4])
def test_intensity_aware_rsm_downsampling_keeps_the_flux(engine, downsample):
    """Clustering k×k RSM texels into one VPL (Kaplanyan 2009, §N.5.2) sums their flux: the injected total must not change
    (float32 sums: 1e-4), and the image may change only by where the merged VPLs sit (means within 10%). The
    setting is the propagating transport's (the gather clusters to its own VPL budget, test_lpv_gather.py)."""
    scene = sphere_scene()
    results = []
    for k in (1, downsample):
        r = engine.render(scene, RenderSettings("lpv", 64, 48, lpv=LpvSettings(
            rsm_downsample=k, bounces=1, max_iterations=16, resolution=16, transport="propagate")))
        results.append(r)
    fluxes = [r.info["cascades"][0]["injected_flux"] for r in results]
    means = [float(r.passes["Diffuse Indirect"].mean()) for r in results]
    print(f"downsample {downsample}: injected {fluxes}, mean Diffuse Indirect {means}")
    assert fluxes[1] == pytest.approx(fluxes[0], rel=1e-4)
    assert means[1] == pytest.approx(means[0], rel=0.10)
