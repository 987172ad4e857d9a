# SPDX-License-Identifier: GPL-3.0-or-later
"""The LPV's gathered transports: "gather" (gpu_kernels/lpv/gather.py: VPLs → surface voxels with fuzzy
visibility, bounce by bounce, with the extrapolated tail) and "transfer" (lpv/transfer.py, the default: the same
kernel from fixed clusters, cached, every bounce summed). Exact oracles: the closed sphere's bounce series, a lit
patch's view factor, a closed partition; and the clustering's flux bookkeeping.
"""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv.gather import VPL_DTYPE, merge
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from support.synthetic import box_quads, lit_patch_error, lit_patch_scene, quad_scene
from support.synthetic import sphere_scene


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _render(engine, scene, size=(64, 48), **kw):
    return engine.render(scene, RenderSettings("lpv", *size, lpv=LpvSettings(**kw)))


def test_merging_keeps_the_flux_and_keeps_floor_and_wall_apart():
    """VPLs on a floor (z = 0, normal +z) and a wall (x = 0, normal +x) meeting at a corner, merged in cubes that
    hold both: the flux per channel must be kept to float32 rounding (1e-5), no merged VPL may mix the two (its
    normal stays on its axis, its position on its plane), and areas add up."""
    rng = np.random.default_rng(1)
    n = 400
    rec = np.zeros(2 * n, VPL_DTYPE)
    rec["position"][:n, :3] = np.c_[rng.uniform(0, 1, n), rng.uniform(0, 1, n), np.zeros(n)]
    rec["normal"][:n, :3] = (0, 0, 1)
    rec["position"][n:, :3] = np.c_[np.zeros(n), rng.uniform(0, 1, n), rng.uniform(0, 1, n)]
    rec["normal"][n:, :3] = (1, 0, 0)
    rec["position"][:, 3] = 1.0
    rec["normal"][:, 3] = 0.01
    rec["flux"][:, :3] = rng.uniform(0.1, 1.0, (2 * n, 3))
    out = merge(rec, 0.5)
    assert 2 * 2 <= len(out) <= 2 * 8  # a 1 m square per surface, cubes of 0.5 m: 4 per surface (corner cubes hold both)
    assert out["flux"][:, :3].sum(axis=0) == pytest.approx(rec["flux"][:, :3].sum(axis=0), rel=1e-5)
    assert out["normal"][:, 3].sum() == pytest.approx(rec["normal"][:, 3].sum(), rel=1e-5)
    floor = out["normal"][:, 2] > 0.999
    wall = out["normal"][:, 0] > 0.999
    assert (floor | wall).all()
    assert np.abs(out["position"][floor, 2]).max() < 1e-6 and np.abs(out["position"][wall, 0]).max() < 1e-6


def test_the_vpl_list_carries_the_injected_flux(engine):
    """The gather's VPLs (clustered to fit `gather_vpls`), the transfer's clusters and the propagation's
    injection read the same RSM: the same flux, whatever the budget (float32 sums: 1e-4; inside a closed sphere
    none escapes)."""
    scene = sphere_scene()
    propagated = _render(engine, scene, transport="propagate", bounces=1, max_iterations=4)
    flux = [propagated.info["cascades"][0]["injected_flux"]]
    for budget in (64, 512):
        r = _render(engine, scene, bounces=1, gather_vpls=budget, transport="gather")
        assert r.info["cascades"][0]["bounces"][0]["vpls"] <= budget
        flux.append(r.info["cascades"][0]["injected_flux"])
        t = \
            _render(engine, scene, bounces=1, gather_vpls=budget).info["cascades"][0]
        # up to twice gather_vpls clusters in a scene of few surface voxels (LpvSettings.transfer_pairs)
        assert t["transport"] == "transfer" and t["clusters"] <= 2 * budget and t["escaped_flux"] == 0
        flux.append(t["injected_flux"])
    print("injected flux, propagate / gather 64 / transfer 64 / gather 512 / transfer 512:", flux)
    assert flux[1:] == pytest.approx([flux[0]] * 4, rel=1e-4)


@pytest.mark.parametrize("transport,bounces,gathered", [("gather", 3, 0), ("gather", 8, 4), ("transfer", 3, 0),
                                                        ("transfer", 8, 0)])
def test_closed_sphere_bounce_series_against_the_analytic_irradiance(engine, transport, bounces, gathered):
    """Inside a closed sphere of albedo ρ with a point light of flux Φ, every bounce is uniform and each is ρ times
    the last: E = E₁·(1 − ρᴺ)/(1 − ρ), E₁ = ρΦ/(4πR²). Three bounces all gathered, and the default (8 bounces, 4
    gathered, 4 extrapolated from the flux ratio of the last two, which should come out ρ). Measured at 32³:
    3 gathered 0.979 of the series (pixels 0.939–1.002), default 0.962 (0.923–0.985), ratio 0.474 for ρ = 0.5;
    1 bounce 1.005·E₁ (the issue's ±15% test, test_lpv.py). Bounds: mean within 10%, every pixel within ±25% of
    the mean (the series is uniform; the spread is the gather's quadrature), ratio within 8% of ρ — each gather
    from voxel clusters delivers ~95% of their light here (their centroids are voxel centres, off the surface by
    up to half a voxel, and receivers in a cluster's own plane are skipped), which the ratio measures.
    The transfer sums every bounce (`gathered` does not apply) with the same kernel and the same bounds."""
    rho = 0.5
    r = _render(engine, sphere_scene(subdivisions=4), resolution=32, bounces=bounces, gathered_bounces=gathered,
                transport=transport)
    e1 = rho * 100.0 / (4 * math.pi)
    expected = e1 * (1 - rho ** bounces) / (1 - rho)
    irradiance = r.passes["Diffuse Indirect"][..., 0] * math.pi
    stats = r.info["cascades"][0]["bounces"]
    print(f"sphere, {transport} {bounces} bounces ({gathered or 'all'} gathered): mean E / expected "
          f"{irradiance.mean() / expected:.3f}, min {irradiance.min() / expected:.3f}, "
          f"max {irradiance.max() / expected:.3f}; passes {stats}")
    assert irradiance.mean() == pytest.approx(expected, rel=0.10)
    assert irradiance.min() > 0.75 * irradiance.mean() and irradiance.max() < 1.25 * irradiance.mean()
    if gathered:
        assert stats[-1]["extrapolated"] == bounces - gathered
        assert stats[-1]["ratio"][0] == pytest.approx(rho, rel=0.08)


@pytest.mark.parametrize("transport", ["gather", "transfer"])
@pytest.mark.parametrize("receiver", ["plate above", "wall beside"])
def test_a_lit_patch_in_a_dark_floor_matches_its_view_factor(engine, receiver, transport):
    """test_vct.py's case for the LPV: a 3 × 2.5 m sunlit patch in a black 6 × 6 m floor, seen from a plate 3 m
    above and a wall 1.5 m beside it. One bounce; exact answer by quadrature. Measured (32³): plate 1.031 of the
    exact mean (per-pixel rel-L1 0.031), wall 1.033 (0.033). Bounds: mean within 10%, rel-L1 below 0.20 — the
    patch's edges are resolved to a fine voxel (9.8 cm here) and its light reaches the receivers from at most
    512 VPL clusters."""
    r = _render(engine, lit_patch_scene(receiver), resolution=32, bounces=1, transport=transport)
    ratio, rel_l1, pixels = lit_patch_error(r.passes)
    assert pixels > 50
    print(f"{receiver} ({transport}): ours / exact view factor {ratio:.3f}, rel-L1 {rel_l1:.3f} over {pixels} pixels")
    assert ratio == pytest.approx(1.0, abs=0.10)
    assert rel_l1 < 0.20


@pytest.mark.parametrize("transport", ["gather", "transfer"])
def test_a_closed_partition_stops_the_gathered_light(engine, transport):
    """Two 2 × 2 × 2 m rooms side by side, a closed 10 cm partition between them (thinner than a cell, 13.8 cm
    here), a point light in the left one: no light can reach the right room (Cycles: exactly 0). The gather's
    visibility meets the partition's planes. Measured: the dark room gets 0.03% (1 bounce) / 0.04% (3 bounces) of
    the lit room's mean Diffuse Indirect; bound 1%. (Before the plane crossings, with a trilinear crossing density,
    it was 2.2% / 4.7%: the density spread the partition over the rays that skimmed its foot.)"""
    quads = box_quads((-2, -1, 0), (-0.05, 1, 2), 0) + box_quads((0.05, -1, 0), (2, 1, 2), 0)
    mats = [Material("white", (0.7, 0.7, 0.7))]
    light = [Light("bulb", "POINT", (1, 1, 1), 100.0, np.array([[1, 0, 0, -1.0], [0, 1, 0, 0], [0, 0, 1, 1.0],
                                                                 [0, 0, 0, 1]]))]
    means = []
    for eye, target in (((-1.9, 0.0, 1.0), (0.0, 0.0, 0.8)), ((1.9, 0.0, 1.0), (0.0, 0.0, 0.8))):
        r = _render(engine, quad_scene(quads, mats, light, eye, target, lens=12.0), resolution=32, bounces=3,
                    transport=transport)
        means.append(float(r.passes["Diffuse Indirect"][..., 0].mean()))
    print(f"{transport}: mean Diffuse Indirect, lit room {means[0]:.4f}, dark room {means[1]:.6f} ({means[1] / means[0]:.3%})")
    assert means[0] > 0
    assert means[1] < 0.01 * means[0]
