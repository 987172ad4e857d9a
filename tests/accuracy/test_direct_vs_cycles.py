# SPDX-License-Identifier: GPL-3.0-or-later
"""Direct light and Diffuse Color against Cycles, per light type and camera kind (issue: foundation).

Each scene is rendered at 160×120 by Bounce GI and by Cycles (two seeds, 128 spp, settings of docs/conventions.md).
Tolerances are the claims:
- Diffuse Direct rel-L1 ≤ 3% per light type. Our light units and falloffs are exact (they match Cycles to 1e-4
  on unshadowed surfaces), so what remains is shadow filtering (PCF edges one texel wide), polygon-light penumbrae
  approximated from a few shadow sample points, pixels straddling two surfaces (Cycles averages them, we take the
  centre's surface), and the reference noise (≤ 0.7% here, checked below so the bound stays meaningful).
- Diffuse Color: ≥ 98% of geometry pixels within 0.01 of Cycles. Only pixels on silhouettes and on edges where two
  materials meet may differ (Cycles jitters within ±0.005 px of the centre), about 1% of the pixels here.
"""
import pytest

LIGHT_SCENES = ["light_sun", "light_point", "light_point_soft", "light_spot", "light_area_square",
                "light_area_disk", "light_mixed", "cornell", "cornell_emissive"]
CAMERA_SCENES = ["textured", "principled", "camera_shift", "camera_ortho"]
SAMPLES = 128
DIRECT_TOLERANCE = 0.03
COLOR_MATCH = 0.98
NOISE_FLOOR_LIMIT = 0.01  # a reference noisier than this could hide a 3% error


@pytest.fixture(scope="module")
def results(compare_examples):
    data = compare_examples(SAMPLES, LIGHT_SCENES + CAMERA_SCENES)
    for name, r in data.items():  # shown with -s or on failure: the measured numbers
        print(f"{name:<20} DiffDir rel-L1 {r['rel_l1']['diffuse_direct']:.4f} (floor {r['noise_floor']['diffuse_direct']:.4f})"
              f"  DiffCol match {r['diffuse_color_match']:.4f}")
    return data


@pytest.mark.parametrize("name", LIGHT_SCENES + CAMERA_SCENES)
def test_diffuse_direct_matches_cycles(results, name):
    r = results[name]
    assert r["noise_floor"]["diffuse_direct"] < NOISE_FLOOR_LIMIT, r["noise_floor"]
    assert r["rel_l1"]["diffuse_direct"] <= DIRECT_TOLERANCE, r


@pytest.mark.parametrize("name", LIGHT_SCENES + CAMERA_SCENES)
def test_diffuse_color_matches_cycles(results, name):
    r = results[name]
    assert r["pixels_compared"] > 0.2 * 160 * 120  # the camera actually sees the scene
    assert r["diffuse_color_match"] >= COLOR_MATCH, r
