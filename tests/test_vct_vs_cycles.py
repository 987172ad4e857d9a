"""VCT against full-bounce Cycles on the typical interiors (issue: Voxel Cone Tracing) — regression bounds.

160×120, default VctSettings (64³, 19 cones, 8 bounces of which 4 gathered with 6 cones) and a single bounce,
against Cycles 128 spp × 2 seeds with 8 bounces. Bounds = today's measured error × 1.05 + 0.05: the references are seeded (the
same Cycles build renders the same noise), so the margin is for a different Cycles build or GL driver moving the
noise (Diffuse Indirect noise floor ~0.07–0.12 here; half of it can move our rel-L1 either way). The issue's
targets are Diffuse Indirect ≤ 20%, Combined ≤ 8%: against these 128-spp references the spot room meets both
(0.151 / 0.056), Cornell Diffuse Indirect (0.164 / 0.081: 0.150 / 0.075 against 2048 spp), the courtyard neither
(0.278 / 0.192). A change that makes VCT worse fails here; one that makes it better should lower these bounds.
The move from 9 to 19 diffuse cones lowered Cornell's bounds and raised the courtyard's (9 cones: 0.260 / 0.180):
narrower cones read more of the courtyard's roof leak (README; vct.VctSettings.diffuse_cones).
"""
import pytest

# measured, rel-L1 Diffuse Indirect / Combined, defaults: cornell 0.164 / 0.081, spot_room 0.151 / 0.056,
# courtyard 0.278 / 0.192
DEFAULT = {"cornell": {"diffuse_indirect": 0.23, "combined": 0.14},
           "spot_room": {"diffuse_indirect": 0.21, "combined": 0.11},
           "courtyard": {"diffuse_indirect": 0.35, "combined": 0.26}}
# measured, 1 bounce: cornell 0.447 / 0.208, spot_room 0.678 / 0.255, courtyard 0.617 / 0.420
ONE = {"cornell": {"diffuse_indirect": 0.52, "combined": 0.27},
       "spot_room": {"diffuse_indirect": 0.77, "combined": 0.32},
       "courtyard": {"diffuse_indirect": 0.70, "combined": 0.49}}


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
    every scene, by a wide margin (measured 0.45 → 0.16, 0.68 → 0.15, 0.62 → 0.28): if it were not, the bounces
    and their tail would not be adding the light they carry."""
    for name in DEFAULT:
        assert default[name]["rel_l1"]["diffuse_indirect"] < 0.7 * one[name]["rel_l1"]["diffuse_indirect"], name
