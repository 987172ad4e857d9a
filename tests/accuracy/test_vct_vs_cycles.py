# SPDX-License-Identifier: GPL-3.0-or-later
"""VCT against full-bounce Cycles on the typical interiors (issue: Voxel Cone Tracing) — regression bounds.

160×120, default VctSettings (64³, 9 cones × 7 sub-rays per pixel, 8 bounces of which 4 gathered with 6 cones) and
a single bounce, against Cycles 128 spp × 2 seeds with 8 bounces. Bounds = today's measured error × 1.05 + 0.05: the
references are seeded (the same Cycles build renders the same noise), so the margin is for a different Cycles build
or GL driver moving the noise (Diffuse Indirect noise floor ~0.07–0.12 here; half of it can move our rel-L1 either
way). The issue's targets are Diffuse Indirect ≤ 20%, Combined ≤ 8%: against these 128-spp references Cornell meets
both (0.117 / 0.060), the spot room both (0.094 / 0.035), the courtyard Diffuse Indirect (0.140 / 0.099; against
2048 spp, whose noise floor is 0.031 / 0.019, 0.080 / 0.059, so both). A change that makes VCT worse fails here;
one that makes it better should lower these bounds. History (Diffuse Indirect / Combined, against 128 spp): 9 → 19
diffuse cones (Cornell 0.185 / 0.092 → 0.164 / 0.081, courtyard 0.260 / 0.180 → 0.278 / 0.192), cone_step's layer
test (Cornell 0.153 / 0.076, spot room 0.147 / 0.054, courtyard 0.219 / 0.152), then the per-pixel sub-rays
(vct/crossing.glsl) with 9 cones (the numbers above). The single bounce is further from full-bounce Cycles than
before the sub-rays (Cornell 0.428 → 0.479): its one-bounce light used to be too bright by 9–21%, which hid part of
the missing bounces; against one-bounce Cycles (2048 spp) it improved, Cornell 0.158 → 0.100, courtyard 0.439 → 0.113.
"""
import pytest

# measured, rel-L1 Diffuse Indirect / Combined, defaults: cornell 0.117 / 0.060, spot_room 0.094 / 0.035,
# courtyard 0.140 / 0.099
DEFAULT = {"cornell": {"diffuse_indirect": 0.18, "combined": 0.12},
           "spot_room": {"diffuse_indirect": 0.15, "combined": 0.09},
           "courtyard": {"diffuse_indirect": 0.20, "combined": 0.16}}
# measured, 1 bounce: cornell 0.479 / 0.225, spot_room 0.725 / 0.272, courtyard 0.689 / 0.468
ONE = {"cornell": {"diffuse_indirect": 0.56, "combined": 0.29},
       "spot_room": {"diffuse_indirect": 0.82, "combined": 0.34},
       "courtyard": {"diffuse_indirect": 0.78, "combined": 0.55}}


@pytest.fixture(scope="module")
def default(compare_examples):
    return compare_examples(128, list(DEFAULT), "--method", "vct")


@pytest.fixture(scope="module")
def one(compare_examples):
    return compare_examples(128, list(ONE), "--method", "vct", "--vct", "bounces=1")


@pytest.mark.parametrize("name", list(DEFAULT))
def test_vct_default_error_does_not_regress(default, name, check_bounds):
    check_bounds(default[name], DEFAULT[name])


@pytest.mark.parametrize("name", list(ONE))
def test_vct_one_bounce_error_does_not_regress(one, name, check_bounds):
    check_bounds(one[name], ONE[name])


def test_more_bounces_get_closer_to_full_bounce_cycles(default, one):
    """Cycles has 8 bounces; ours with 8 (extrapolated past 4) must be nearer on Diffuse Indirect than with 1 in
    every scene, by a wide margin (measured 0.48 → 0.12, 0.73 → 0.09, 0.69 → 0.14): if it were not, the bounces
    and their tail would not be adding the light they carry."""
    for name in DEFAULT:
        assert default[name]["rel_l1"]["diffuse_indirect"] < 0.7 * one[name]["rel_l1"]["diffuse_indirect"], name
