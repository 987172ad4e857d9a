"""VCT against full-bounce Cycles on the typical interiors (issue: Voxel Cone Tracing) — regression bounds.

160×120, default VctSettings (64³, 19 cones, 8 bounces of which 4 gathered with 6 cones) and a single bounce,
against Cycles 128 spp × 2 seeds with 8 bounces. Bounds = today's measured error × 1.05 + 0.05: the references are seeded (the
same Cycles build renders the same noise), so the margin is for a different Cycles build or GL driver moving the
noise (Diffuse Indirect noise floor ~0.07–0.12 here; half of it can move our rel-L1 either way). The issue's
targets are Diffuse Indirect ≤ 20%, Combined ≤ 8%: against these 128-spp references Cornell meets both (0.153 /
0.076), the spot room both (0.147 / 0.054), the courtyard neither (0.219 / 0.152; against 2048 spp 0.178 / 0.125,
so Diffuse Indirect within the target there). A change that makes VCT worse fails here; one that makes it better
should lower these bounds. History: 9 → 19 diffuse cones (Cornell 0.185 / 0.092 → 0.164 / 0.081, courtyard 0.260 /
0.180 → 0.278 / 0.192), then cone_step's layer test (the numbers above).
"""
import pytest

# measured, rel-L1 Diffuse Indirect / Combined, defaults: cornell 0.153 / 0.076, spot_room 0.147 / 0.054,
# courtyard 0.219 / 0.152
DEFAULT = {"cornell": {"diffuse_indirect": 0.22, "combined": 0.13},
           "spot_room": {"diffuse_indirect": 0.21, "combined": 0.11},
           "courtyard": {"diffuse_indirect": 0.28, "combined": 0.21}}
# measured, 1 bounce: cornell 0.428 / 0.199, spot_room 0.669 / 0.252, courtyard 0.646 / 0.439
ONE = {"cornell": {"diffuse_indirect": 0.50, "combined": 0.26},
       "spot_room": {"diffuse_indirect": 0.76, "combined": 0.32},
       "courtyard": {"diffuse_indirect": 0.73, "combined": 0.52}}


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
    every scene, by a wide margin (measured 0.43 → 0.15, 0.67 → 0.15, 0.65 → 0.22): if it were not, the bounces
    and their tail would not be adding the light they carry."""
    for name in DEFAULT:
        assert default[name]["rel_l1"]["diffuse_indirect"] < 0.7 * one[name]["rel_l1"]["diffuse_indirect"], name
