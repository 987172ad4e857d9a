# SPDX-License-Identifier: GPL-3.0-or-later
"""Voxel Cone Tracing (Crassin et al. 2011; Freed 2018): properties that must hold by construction, with tolerances and their reasons.

(a) White furnace: a closed box whose walls all emit Le and reflect ρ, no lights. Emissive triangles are lights, so
    Diffuse Direct = Le (irradiance π·Le from the walls all round) and light that bounced k times arrives with
    radiance ρ^k·Le. With N indirect bounces the walls seen by the final gather carry L_N = Le·Σ_{i=1..N} ρ^i of
    reflected light, so Diffuse Indirect = E/π = Le·(ρ + ρ² + … + ρ^N) → Le·ρ/(1 − ρ) as N → ∞.
(b) A sunlit floor beside a wall: the wall receives indirect light near the analytic view-factor value; the floor,
    which sees only the unlit wall and a black sky, receives none (no self-illumination).
(c) Mipmapping conserves the filtered medium's emission exactly (isotropic), and a wall one voxel thick stays
    opaque at every level (both modes); the leak through a thin wall between a lit and a dark room is measured.
(d) Settings validation and the cone table (weights integrate the cosine exactly).
Runs on Mesa llvmpipe: 32³ grids and ≤ 80×60 images keep it to ~20 s.
"""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.vct.cones import cone_table
from bounce_gi.gpu_kernels.vct.trace import read_ao, read_level
from bounce_gi.gpu_kernels.vct.volumes import level_sizes, mip_levels, vct_grid
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.synthetic import box_quads, lit_patch_error, lit_patch_scene, quad, quad_scene


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _render(engine, scene, size=(40, 30), **kw):
    """The cone estimator at every pixel (indirect_scale 1; tests/gpu/test_vct_upsample.py checks the upsampling)."""
    settings = RenderSettings("vct", *size, vct=VctSettings(**{"resolution": 32, "indirect_scale": 1, **kw}))
    return engine.render(scene, settings)


# --------------------------------------------------------------------------------------------- (a) white furnace
RHO, LE = 0.5, 1.0


@pytest.fixture(scope="module")
def furnace():
    quads = box_quads((-1, -1, -1), (1, 1, 1), 0)
    return quad_scene(quads, [Material("wall", (RHO,) * 3, emission=(LE,) * 3)], [], (0.0, -0.5, 0.1), (0.3, 1.0, -0.2))


@pytest.mark.parametrize("anisotropic", [False, True])
def test_white_furnace_converges_to_the_geometric_series(engine, furnace, anisotropic):
    rows = []
    for bounces in (1, 2, 3):
        r = _render(engine, furnace, bounces=bounces, anisotropic=anisotropic)
        hit = r.passes["Depth"][..., 0] < 1e9
        direct = float(r.passes["Diffuse Direct"][hit].mean())
        indirect = float(r.passes["Diffuse Indirect"][hit].mean())
        expected = LE * sum(RHO ** i for i in range(1, bounces + 1))
        rows.append((bounces, direct, indirect, expected))
        print(f"furnace {'aniso' if anisotropic else 'iso'} N={bounces}: Diffuse Direct {direct:.4f} (exact {LE}), "
              f"Diffuse Indirect {indirect:.4f} (exact {expected:.4f}, ratio {indirect / expected:.4f}); "
              f"flux per bounce {[round(b['flux'][0], 2) for b in r.info['bounces']]}")
        # Direct light is the exact polygon integral, shadowed through shadow cubes: 1% (measured 0.5%).
        assert direct == pytest.approx(LE, rel=0.01)
        if anisotropic:
            # Coarse texels at the box's edges are half outside the box, so their mean coverage lets part of a cone
            # through to the black world (vct/mipmap.glsl): measured 2.1%, 3.2%, 3.9% low for N = 1, 2, 3 at 32³
            # (2.4%, 3.4%, 4.1% with the volumetric per-pixel march before sub-rays; 5.8%, 7.0%, 7.7% before
            # cone_step's layer test, when the wall beside a cone's start absorbed part of it through the filter).
            assert 0.93 * expected < indirect < 1.01 * expected
        else:
            # Isotropic voxels take the brighter side, which inside a closed box is always the lit one: measured
            # 0.1% low; 2% allows for the voxelised geometry.
            assert indirect == pytest.approx(expected, rel=0.02)
    # Each bounce adds less (ρ < 1): the series converges, monotonically.
    gains = np.diff([0.0] + [r[2] for r in rows])
    assert np.all(gains > 0) and np.all(np.diff(gains) < 0)


def test_extrapolated_bounces_match_gathered_ones_in_the_furnace(engine, furnace):
    """In a white furnace every bounce adds a fixed fraction of the light of the one before, so the geometric tail
    (gathered_bounces) must reproduce gathering all of them. That fraction is ρ less what the voxelised box's edge
    texels leak per bounce: the gathered run shows B3/B2 = 0.481 at 32³, and the tail's estimate from bounces 1–2
    is 0.473, from 1–3 0.481 — so the ratio must lie in [0.45, ρ]. Tolerance on the result 1.5%: measured 0.98%
    low with 2 gathered bounces (the early ratio is a little low), 0.2% with 3."""
    full = _render(engine, furnace, bounces=6, gathered_bounces=0)  # every bounce gathered
    assert len(full.info["bounces"]) == 6 and not full.info["bounces"][-1].get("extrapolated")
    hit = full.passes["Depth"][..., 0] < 1e9
    reference = float(full.passes["Diffuse Indirect"][hit].mean())
    for gathered in (2, 3):
        r = _render(engine, furnace, bounces=6, gathered_bounces=gathered)
        value = float(r.passes["Diffuse Indirect"][hit].mean())
        tail = r.info["bounces"][-1]
        print(f"furnace gathered {gathered} of 6: {value:.4f} vs all gathered {reference:.4f}; ratio {tail['ratio']}")
        assert tail["extrapolated"] and tail["bounce"] == 6 and len(r.info["bounces"]) == gathered + 1
        assert 0.45 <= tail["ratio"][0] <= RHO
        assert value == pytest.approx(reference, rel=0.015)
    # Without the tail, stopping at 2 bounces is far off (≈ 1/4 of the light of bounces 3–6 missing): the test
    # above is not passing merely because the bounce count barely matters.
    two = _render(engine, furnace, bounces=2)
    assert float(two.passes["Diffuse Indirect"][hit].mean()) < 0.9 * reference


# ------------------------------------------------------------------------------------- (b) lit floor and a wall
def _view_factor_floor(p, n, floor_lo, floor_hi, samples=40000):
    """Cosine-weighted fraction of the hemisphere of n at p that sees the floor rectangle z = 0 (Monte Carlo)."""
    rng = np.random.default_rng(7)
    u = rng.random((samples, 2))
    phi, ct = 2 * np.pi * u[:, 0], np.sqrt(u[:, 1])
    st = np.sqrt(1 - ct * ct)
    t1 = np.cross(n, (0, 0, 1.0))
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(n, t1)
    d = (st * np.cos(phi))[:, None] * t1 + (st * np.sin(phi))[:, None] * t2 + ct[:, None] * n
    t = -p[2] / np.minimum(d[:, 2], -1e-12)
    q = p + d * t[:, None]
    ok = (d[:, 2] < 0) & np.all((q[:, :2] >= floor_lo) & (q[:, :2] <= floor_hi), axis=1)
    return ok.mean()


def test_lit_floor_lights_the_wall_and_nothing_lights_the_floor(engine):
    sun = Light("sun", "SUN", (1, 1, 1), 3.0, np.eye(4))  # straight down: the wall gets no direct light
    floor = quad([(-2, -2, 0), (2, -2, 0), (2, 1, 0), (-2, 1, 0)], (0, 0, 1))
    wall = quad([(-2, 1, 0), (2, 1, 0), (2, 1, 2), (-2, 1, 2)], (0, -1, 0))
    scene = quad_scene([(floor, 0), (wall, 0)], [Material("white", (0.8, 0.8, 0.8))], [sun], (0, -4, 3), (0, 0.5, 0.3),
                   lens=20.0)
    r = _render(engine, scene, size=(80, 60), bounces=1)
    di, pos = r.passes["Diffuse Indirect"][..., 0], r.passes["Position"]
    hit = r.passes["Depth"][..., 0] < 1e9
    on_wall = hit & (np.abs(pos[..., 1] - 1.0) < 1e-3)
    on_floor = hit & (np.abs(pos[..., 2]) < 1e-3)
    floor_radiance = 0.8 * 3.0 / math.pi
    ys, xs = np.nonzero(on_wall)
    pick = np.linspace(0, len(ys) - 1, 12).astype(int)
    exact = np.array([floor_radiance * _view_factor_floor(pos[ys[i], xs[i]], np.array([0, -1.0, 0]),
                                                          (-2, -2), (2, 1)) for i in pick])
    ours = di[ys[pick], xs[pick]]
    print("wall Diffuse Indirect, ours vs view factor:", np.round(ours, 3), np.round(exact, 3),
          f"mean ratio {ours.mean() / exact.mean():.3f}")
    # The cones see the floor through their sub-rays (vct/crossing.glsl), so single pixels can be off by a sub-ray
    # at the floor's edges; the mean over the wall is measured 0.976 of the view factor with the default 16 cones × 5
    # sub-rays (0.956 with 9 × 7; 32³; 1.05 with 19 cones and the volumetric march before sub-rays). Bound: within
    # 10%.
    assert ours.mean() == pytest.approx(exact.mean(), rel=0.10)
    assert np.all(ours > 0.02)
    # The floor sees the unlit wall and the black world only: no indirect light at all (bounces = 1).
    assert float(di[on_floor].max()) < 1e-4


@pytest.mark.parametrize("receiver", ["plate above", "wall beside"])
def test_a_lit_patch_in_a_dark_floor_matches_its_view_factor(engine, receiver):
    """A 3 × 2.5 m lit patch in a black 6 × 6 m floor, seen from a plate 3 m above it and from a wall 1.5 m beside
    it (the courtyard's case: bounced light from a sunlit patch). Before the per-pixel sub-rays (vct/crossing.glsl)
    the cones read the patch at their own coarse level, which spread its light over neighbouring cones, and skimmed
    the floor without meeting it: the plate came out 1.61× and the wall 1.51× the exact integral (64³, 19 cones).
    Measured since, with 9 cones × 7 sub-rays: plate 0.963 (per-sample rel-L1 0.059), wall 1.008 (0.083); with the
    default 16 × 5 (two rings of cones, whose wider outer cones read the patch's edge a little long): plate 1.074
    (0.103), wall 1.071 (0.134); 19 × 4: 1.031 (0.052), 1.045 (0.075). Bounds: mean within 10%, rel-L1 below 0.15 —
    the cone set's quadrature and the voxel's size (6.4 cm) at the patch's edges."""
    r = _render(engine, lit_patch_scene(receiver), resolution=64, bounces=1)
    ratio, rel_l1, pixels = lit_patch_error(r.passes)
    assert pixels > 50
    print(f"{receiver}: ours / exact view factor {ratio:.3f}, rel-L1 {rel_l1:.3f} over {pixels} pixels")
    assert ratio == pytest.approx(1.0, abs=0.10)
    assert rel_l1 < 0.15


# ---------------------------------------------------------------------------------------------- (c) mipmapping
def _volumes(engine, scene, anisotropic):
    """Render once, then read every mip level of the vct_mipmap pass's volumes (GL thread)."""
    _render(engine, scene, anisotropic=anisotropic)
    pipe = engine.pipeline

    def grab(ctx):
        vols = pipe.cache.entries["vct_mipmap"].value
        return vols.grid, [[read_level(ctx, pipe.programs, t, vols.grid, level) for level in range(vols.levels)]
                           for t in vols.textures]
    return engine.worker.call(grab)


def _sunlit_room():
    sun = Light("sun", "SUN", (1, 1, 1), 4.0, np.linalg.inv(cam.look_at((1, -1, 3), (0, 0, 0), (0, 0, 1))))
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))  # open top
    quads += box_quads((-0.3, -0.3, 0.0), (0.3, 0.3, 0.7), 1, inward=False)
    return quad_scene(quads, [Material("white", (0.7, 0.7, 0.7)), Material("red", (0.8, 0.2, 0.1))], [sun],
                  (0.0, -0.9, 1.5), (0.0, 0.5, 0.3))


def test_isotropic_mip_conserves_emission(engine):
    grid, (levels,) = _volumes(engine, _sunlit_room(), anisotropic=False)
    # Stored rgb = τ·S with τ per texel crossing: the parent holds 2 × the mean of its 8 children (the mean extinction
    # coefficient over a texel twice as long), so Σ τ·S·V² — the filtered medium's emitted power — is the same on
    # every level. Exact up to float32 summation (1e-5).
    power = [levels[l][..., :3].astype(np.float64).sum(axis=(0, 1, 2)) * 4.0 ** l for l in range(len(levels))]
    print("isotropic Σ τ·S·V² per level:", [np.round(p, 3).tolist() for p in power])
    assert power[0].min() > 0
    for p in power[1:]:
        assert np.allclose(p, power[0], rtol=1e-5)


@pytest.mark.parametrize("anisotropic", [False, True])
def test_a_wall_one_voxel_thick_stays_opaque_at_every_level(engine, anisotropic):
    wall_x = 0.05  # a wall across the whole grid, normal along x
    quads = [(quad([(wall_x, -1, 0), (wall_x, 1, 0), (wall_x, 1, 2), (wall_x, -1, 2)], (-1, 0, 0)), 0)]
    quads += [(quad([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], (0, 0, 1)), 0)]  # a floor, for the extent
    scene = quad_scene(quads, [Material("grey", (0.5, 0.5, 0.5))], [Light("p", "POINT", (1, 1, 1), 50.0,
                   np.array([[1, 0, 0, -0.5], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1.0]]))], (-0.9, -0.9, 1.5),
                   (0, 0, 0.5))
    grid, volumes = _volumes(engine, scene, anisotropic)
    ix = int(np.floor((wall_x - grid.origin[0]) / grid.cell))
    travel_x = volumes[0]  # isotropic, or anisotropic "travelling +x"
    for level, data in enumerate(travel_x):
        k = ix >> level
        nz, ny = data.shape[:2]
        # Optical depth met crossing the wall's layer of texels along x, in the middle of the wall (away from the
        # floor and the grid's empty margins): the wall's τ_max = −ln(1e-3) on every level (to float rounding).
        tau = data[nz // 4: 3 * nz // 4, ny // 4: 3 * ny // 4, k, 3]
        assert np.allclose(tau, -math.log(1e-3), rtol=1e-4), (level, tau.min(), tau.max())


def test_thin_wall_leak_isotropic_vs_anisotropic(engine):
    """Two rooms sharing a wall at x = 0, a point light in the left one: no light can reach the right room."""
    white = 0
    quads = box_quads((-2, -1, 0), (2, 1, 2), white)
    quads += [(quad([(0, -1, 0), (0, 1, 0), (0, 1, 2), (0, -1, 2)], (1, 0, 0)), white)]
    light = Light("bulb", "POINT", (1, 1, 1), 200.0, np.array([[1, 0, 0, -1.0], [0, 1, 0, 0], [0, 0, 1, 1.5],
                                                                [0, 0, 0, 1.0]]))
    scene = quad_scene(quads, [Material("white", (0.8, 0.8, 0.8))], [light], (0.0, -0.95, 1.9), (0.0, 1.0, 0.2),
                   lens=10.0)
    leaks = {}
    for anisotropic, bounces in ((False, 1), (True, 1), (True, 8)):
        r = _render(engine, scene, size=(80, 60), anisotropic=anisotropic, bounces=bounces)
        di, pos = r.passes["Diffuse Indirect"].mean(axis=-1), r.passes["Position"]
        hit = r.passes["Depth"][..., 0] < 1e9
        lit, dark = hit & (pos[..., 0] < -0.3), hit & (pos[..., 0] > 0.3)
        leaks[anisotropic, bounces] = float(di[dark].mean() / di[lit].mean())
    print("thin-wall leak (dark room / lit room Diffuse Indirect):", {k: round(v, 4) for k, v in leaks.items()})
    # Anisotropic voxels show the dark room the wall's dark face; what remains comes through the voxels where the
    # wall meets the floor, ceiling and side walls (their faces average both rooms' floor) and through coarse texels
    # straddling those junctions: one bounce, measured 1.4% at 32³ with the per-pixel sub-rays, which read what
    # they cross one level finer than their cone but at full width, so near the junctions they see the lit room's
    # floor through those texels (0.74% with the volumetric march; 1.4% before cone_step's layer test); bound 3%.
    assert leaks[True, 1] < 0.03
    # Every further bounce re-reflects what leaked and leaks again: with the default 8 bounces measured 3.0%
    # (2.0% with the volumetric march, 3.6% before the layer test; 5.5% since the lattice's boundaries moved to
    # (k + 1/3) cells, common/grid.LATTICE_PHASE, which put the wall at x = 0 off a voxel boundary); bound 6%.
    assert leaks[True, 8] < 0.06
    # Isotropic voxels show the lit face on both sides (the classic VCT leak): measured 20% with one bounce on the
    # whole-cell lattice, 10.6% since the phase (the wall now inside a voxel, not on a boundary), 8× the anisotropic
    # leak; bound 5×.
    assert leaks[False, 1] > 5 * max(leaks[True, 1], 1e-4)


def test_a_sunlit_roof_top_does_not_light_the_room_below(engine):
    """A 3 × 3 × 2 m room, roofed except for a 0.6 × 0.6 m opening, the sun straight above: it lights the roof's top
    and a floor patch. The roof's top cannot be seen from inside, so after one bounce the walls' Diffuse Indirect
    must not depend on the roof's albedo (the underside is unlit, hence black, either way). Coarse texels straddling
    the roof used to show its lit top to cones passing under it: the upper walls came out 1.28× as bright with a
    white roof as with a black one before the layer test of cone_step (vct/common.glsl); measured 1.000 since, and
    with the per-pixel sub-rays (vct/crossing.glsl: a sub-ray under the roof never crosses it). Bound 2%, for float
    rounding across drivers."""
    walls = box_quads((-1.5, -1.5, 0), (1.5, 1.5, 2), 0, skip=((2, "hi"),))
    roof = [(quad([(a, c, 2), (b, c, 2), (b, d, 2), (a, d, 2)], (0, 0, -1)), 1)
            for a, b, c, d in ((-1.5, 1.5, 0.3, 1.5), (-1.5, 1.5, -1.5, -0.3), (-1.5, -0.3, -0.3, 0.3),
                               (0.3, 1.5, -0.3, 0.3))]
    sun = Light("sun", "SUN", (1, 1, 1), 5.0, np.eye(4))
    upper = {}
    for roof_albedo in (0.8, 0.0):
        mats = [Material("white", (0.7, 0.7, 0.7)), Material("roof", (roof_albedo,) * 3)]
        scene = quad_scene(walls + roof, mats, [sun], (1.2, -1.2, 0.6), (-1.5, 1.5, 1.6), lens=14.0)
        r = _render(engine, scene, size=(60, 45), bounces=1)
        di, pos, nrm = r.passes["Diffuse Indirect"].mean(axis=-1), r.passes["Position"], r.passes["Normal"]
        on_wall = (r.passes["Depth"][..., 0] < 1e9) & (np.abs(nrm[..., 2]) < 0.1) & (pos[..., 2] > 1.2)
        assert on_wall.sum() > 200
        upper[roof_albedo] = float(di[on_wall].mean())
    print("upper walls' Diffuse Indirect, white roof / black roof:", upper, upper[0.8] / upper[0.0])
    assert upper[0.0] > 0.0 and upper[0.8] / upper[0.0] == pytest.approx(1.0, abs=0.02)


# --------------------------------------------------------------------------------- pipeline: passes, AO, info
def test_passes_rerun_only_downstream_and_ao_is_sky_visibility(engine, furnace):
    sun = Light("sun", "SUN", (1, 1, 1), 3.0, np.eye(4))
    floor = quad([(-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)], (0, 0, 1))
    scene = quad_scene([(floor, 0)], [Material("white", (0.8, 0.8, 0.8))], [sun], (0, -3, 2), (0, 0, 0), lens=20.0)
    r = _render(engine, scene, bounces=1)
    assert r.info["grid"] == [32, 32, 8] and r.info["levels"] == mip_levels(32) and r.info["anisotropic"]
    assert r.info["occupied_voxels"] > 0 and len(r.info["bounces"]) == 1
    r = _render(engine, scene, bounces=2)
    assert {"vct_voxelize", "vct_inject", "vct_mipmap"} <= set(r.skipped)
    assert "vct_bounce" not in r.skipped and "vct_trace" not in r.skipped
    assert [b["bounce"] for b in r.info["bounces"]] == [1, 2]
    # A lone floor under a black sky: every cone leaves the grid, so AO (sky visibility) is 1 and nothing lights
    # the floor indirectly; a closed box: no cone should leave, AO should be 0.
    pipe = engine.pipeline
    ao = engine.worker.call(lambda ctx: read_ao(pipe.cache.entries["vct_trace"].value["indirect"]))
    hit = r.passes["Depth"][..., 0] < 1e9
    assert float(ao[hit].min()) > 0.999 and float(r.passes["Diffuse Indirect"][hit].max()) < 1e-6
    r = _render(engine, furnace)
    ao = engine.worker.call(lambda ctx: read_ao(pipe.cache.entries["vct_trace"].value["indirect"]))
    hit = r.passes["Depth"][..., 0] < 1e9
    # The furnace loses 5% of its light through coarse texels at the box's edges (see above), so AO is not 0 there:
    # measured mean 0.04, max 0.13; bounds 0.08 and 0.2.
    print(f"closed box AO: mean {float(ao[hit].mean()):.3f}, max {float(ao[hit].max()):.3f}")
    assert float(ao[hit].mean()) < 0.08 and float(ao[hit].max()) < 0.2


# ------------------------------------------------------------------------------------ (d) settings and cones
@pytest.mark.parametrize("bad", [dict(resolution=8), dict(resolution=1024), dict(diffuse_cones=4),
                                 dict(diffuse_cones=10), dict(diffuse_cones=12), dict(diffuse_cones=17),
                                 dict(diffuse_cones=34), dict(bounce_cones=14), dict(diffuse_aperture=-1.0),
                                 dict(diffuse_aperture=90.0), dict(diffuse_aperture=1.0),
                                 dict(max_distance=-1.0), dict(bounces=0), dict(bounces=17),
                                 dict(gathered_bounces=1), dict(gathered_bounces=17), dict(gathered_bounces=-1),
                                 dict(bounce_cones=4), dict(bounce_cones=10),
                                 dict(step_multiplier=0.0), dict(step_multiplier=3.0), dict(start_offset=-0.1),
                                 dict(roughness_cutoff=1.5), dict(ao_distance=-1.0), dict(indirect_scale=3),
                                 dict(indirect_scale=0), dict(temporal_frames=-1),
                                 dict(temporal_frames=1000), dict(cone_rotation=math.inf), dict(subrays=0),
                                 dict(subrays=8), dict(subrays=2.5), dict(epsilon=-0.1), dict(epsilon=1.0)])
def test_settings_are_validated(bad):
    with pytest.raises(ValueError):
        VctSettings(**bad)


def test_defaults_are_valid_and_keys_separate_passes():
    s = VctSettings()
    assert s.resolution == 64 and s.diffuse_cones == 16 and s.subrays == 5 and s.bounces == 8
    assert s.gathered_bounces == 4
    assert s.anisotropic and s.bounce_cones == 6
    for change in (dict(bounces=3), dict(gathered_bounces=2), dict(bounce_cones=9), dict(epsilon=0.01)):
        # re-run vct_bounce only
        assert VctSettings(**change).key("trace") == s.key("trace")
        assert VctSettings(**change).key("bounce") != s.key("bounce")
    assert VctSettings(ao_distance=1.0).key("bounce") == s.key("bounce")
    # The bounce gathers use bounce_cones; diffuse_cones only when bounce_cones = 0 ("same as diffuse").
    assert VctSettings(diffuse_cones=19).key("bounce") == s.key("bounce")
    assert VctSettings(diffuse_cones=19).key("trace") != s.key("trace")
    assert VctSettings(diffuse_cones=19, bounce_cones=0).key("bounce") != VctSettings(bounce_cones=0).key("bounce")
    assert s.specular_cone  # on by default: pixels with no glossy closure skip it (vct/specular.py)
    assert s.indirect_scale == 2  # the diffuse cones at every other pixel, upsampled (vct/upsample.py)
    for change in (dict(indirect_scale=1), dict(temporal_frames=4), dict(cone_rotation=10.0), dict(subrays=7)):
        assert VctSettings(**change).key("trace") != s.key("trace") and VctSettings(**change).key("specular") == \
            s.key("specular") and VctSettings(**change).key("bounce") == s.key("bounce")
    assert VctSettings(roughness_cutoff=0.2).key("specular") != s.key("specular")
    assert VctSettings(roughness_cutoff=0.2).key("trace") == s.key("trace")


@pytest.mark.parametrize("count", [5, 6, 7, 8, 9, 13, 16, 19, 25, 31])
def test_cone_weights_integrate_the_cosine_exactly(count):
    dirs, weights, tans = cone_table(count)
    assert len(dirs) == len(weights) == count and np.allclose(np.linalg.norm(dirs, axis=1), 1.0)
    assert weights.sum() == pytest.approx(math.pi, rel=1e-12)  # uniform radiance L → E = π·L exactly
    # Independently of cone_table's closed forms: the regions are a cap and rings of equal solid angle 2π/n, cut
    # into equal sectors. Midpoint quadrature of ∫cosθ dω and of the cosine-weighted mean direction per ring.
    rings = [1, count - 1] if count <= 9 else [1, (count - 1) // 3, 2 * (count - 1) // 3]
    theta = np.linspace(0, math.pi / 2, 200001)
    mid, dt = (theta[1:] + theta[:-1]) / 2, theta[1] - theta[0]
    first = 0
    for k, m in enumerate(rings):
        hi, lo = 1 - first / count, 1 - (first + m) / count   # cosθ at the ring's inner / outer edge
        inside = (np.cos(mid) <= hi) & (np.cos(mid) > lo)
        dphi = 2 * math.pi / m
        w = dphi * (np.cos(mid) * np.sin(mid) * dt)[inside].sum()
        assert np.allclose(weights[first:first + m], w, rtol=1e-3), (k, weights[first:first + m], w)
        # Mean direction of one sector φ ∈ [−Δφ/2, Δφ/2]: horizontal 2·sin(Δφ/2)·∫sin²θcosθ,
        # vertical Δφ·∫cos²θ sinθ.
        horizontal = (2 * math.sin(dphi / 2) if m > 1 else 0.0) * (np.sin(mid) ** 2 * np.cos(mid) * dt)[inside].sum()
        vertical = dphi * (np.cos(mid) ** 2 * np.sin(mid) * dt)[inside].sum()
        assert np.allclose(dirs[first:first + m, 2], math.cos(math.atan2(horizontal, vertical)), atol=1e-3)
        if m > 1:  # inside its ring, and the sectors spread evenly around the normal
            assert np.all(dirs[first:first + m, 2] < hi) and np.all(dirs[first:first + m, 2] > max(lo, 0.0))
            assert np.allclose(dirs[first:first + m, :2].sum(axis=0), 0.0, atol=1e-12)
        first += m
    # Equal solid angles 2π/n, and the derived aperture is that of a cone of the same solid angle.
    assert 2 * math.pi * (1 - math.cos(math.atan(tans[0]))) == pytest.approx(2 * math.pi / count)


def test_second_ring_is_turned_half_a_sector():
    dirs, _, _ = cone_table(19)
    phi1 = np.degrees(np.arctan2(dirs[1:7, 1], dirs[1:7, 0])) % 360
    phi2 = np.degrees(np.arctan2(dirs[7:, 1], dirs[7:, 0])) % 360
    assert np.allclose(np.sort(phi1), np.arange(6) * 60.0) and np.allclose(np.sort(phi2), 15.0 + np.arange(12) * 30.0)


def test_grid_is_padded_so_mip_levels_nest():
    scene = quad_scene(box_quads((0, 0, 0), (3.0, 2.0, 0.4), 0), [Material("m")], [], (1, -3, 1), (1, 1, 0.2))
    s = VctSettings(resolution=64)
    grid = vct_grid(scene, s)
    align = 2 ** (mip_levels(64) - 1)
    assert all(n % align == 0 for n in grid.size) and max(grid.size) == 64
    assert level_sizes(grid, mip_levels(64))[-1] == tuple(n // align for n in grid.size)
