"""LPV against Cycles on the typical interiors (issue: Light Propagation Volumes) — regression bounds.

160×120, 32³ grid, Cycles 128 spp × 2 seeds. Two comparisons on each typical interior, as the issue asks: with
full bounces (ours 3, Cycles 8) and with the same single bounce on both sides. The bounds hold today's measured
errors × 1.05 + 0.05: the references are seeded (the same Cycles build renders the same noise), so the margin is for
a different Cycles build or GL driver moving the noise — on Diffuse Indirect the noise floor is ~0.07 here, and
half of it can move our rel-L1 either way; errors well above 1 come from pixels the reference has nearly black,
hence the relative part. They are NOT the issue's targets (Diffuse Indirect ≤ 25%, Combined ≤ 10%), and they are
far from them: the 2-band propagation is diffusive, and the measured one-bounce spot room has 2.6× Cycles'
indirect light, nearly all of it on the spot-lit floor itself — the floor's own VPLs, injected half a cell above
it, spread sideways (the 2-band clamped-cosine lobe is 1/3 of its peak at 90°) and the floor's blocking potential
stops that flux at the floor (see the closing note of the LPV work). A change that makes LPV worse fails here; one
that makes it better should lower these bounds.
"""
import pytest

# measured, rel-L1 Diffuse Indirect / Combined (full bounces): cornell 0.692 / 0.331, spot_room 1.233 / 0.472,
# courtyard 0.967 / 0.657
FULL = {"cornell": {"diffuse_indirect": 0.78, "combined": 0.40},
        "spot_room": {"diffuse_indirect": 1.35, "combined": 0.55},
        "courtyard": {"diffuse_indirect": 1.07, "combined": 0.74}}
# measured (1 bounce each side): cornell 0.887 / 0.309, spot_room 2.878 / 0.439, courtyard 1.907 / 0.739
ONE_BOUNCE = {"cornell": {"diffuse_indirect": 0.99, "combined": 0.38},
              "spot_room": {"diffuse_indirect": 3.07, "combined": 0.52},
              "courtyard": {"diffuse_indirect": 2.06, "combined": 0.83}}


@pytest.fixture(scope="module")
def full(compare_examples):
    return compare_examples(128, list(FULL), "--method", "lpv", "--lpv", "bounces=3")


@pytest.fixture(scope="module")
def one_bounce(compare_examples):
    return compare_examples(128, list(ONE_BOUNCE), "--method", "lpv", "--bounces", 1, "--lpv", "bounces=1")


@pytest.mark.parametrize("name", list(FULL))
def test_lpv_full_bounce_error_does_not_regress(full, name, check_bounds):
    check_bounds(full[name], FULL[name])


@pytest.mark.parametrize("name", list(ONE_BOUNCE))
def test_lpv_one_bounce_error_does_not_regress(one_bounce, name, check_bounds):
    check_bounds(one_bounce[name], ONE_BOUNCE[name])
