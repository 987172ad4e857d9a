# SPDX-License-Identifier: GPL-3.0-or-later
"""VCT against full-bounce Cycles on the typical interiors (issue: Voxel Cone Tracing) — regression bounds.

160×120, default VctSettings (64³, 16 cones × 5 sub-rays at every other pixel and upsampled, 8 bounces of which 4
gathered with 6 cones) and a single bounce, against the committed Cycles references of examples/references/
(TRANSPORT: 4096 spp × 2 seeds, 8 bounces; the test never renders Cycles). The issue's targets are Diffuse Indirect
≤ 20%, Combined ≤ 8% against full-bounce Cycles; where a scene meets one it is asserted too. The single bounce is
compared with full-bounce Cycles on purpose: it measures how much light the bounces add
(test_more_bounces_get_closer_to_full_bounce_cycles).

Bounds: the measured value + 2 × the reference's noise floor + 0.001, rounded up to 3 decimals (the rule of
test_examples_vs_cycles.py, whose docstring derives it). A change that makes VCT worse fails here; one that makes it
better should lower these bounds. History (Diffuse Indirect / Combined, against the 128-spp references these tests
used before): 9 → 19 diffuse cones (Cornell 0.185 / 0.092 → 0.164 / 0.081, courtyard 0.260 / 0.180 → 0.278 /
0.192), cone_step's layer test (Cornell 0.153 / 0.076, spot room 0.147 / 0.054, courtyard 0.219 / 0.152), then the
per-pixel sub-rays (vct/crossing.glsl) with 9 cones (Cornell 0.117 / 0.060, spot room 0.094 / 0.035, courtyard
0.140 / 0.099).
"""
import pytest

# Measured 2026-12-06 against the 4096-spp references (rel-L1 Diffuse Indirect / Combined; noise floor DI / Combined),
# defaults (16 cones × 5 sub-rays since stop 41; 9 × 7 before: cornell 0.1005 / 0.0513, spot_room 0.0522 / 0.0194,
# courtyard 0.0910 / 0.0663): cornell 0.0912 / 0.0455 (0.0114 / 0.0050), spot_room 0.0504 / 0.0189 (0.0127 /
# 0.0047), courtyard 0.0890 / 0.0649 (0.0202 / 0.0136); the courtyard's Combined bound is the target, lower
# than the rule's 0.094.
DEFAULT = {"cornell": {"diffuse_indirect": 0.115, "combined": 0.057},
           "spot_room": {"diffuse_indirect": 0.077, "combined": 0.030},
           "courtyard": {"diffuse_indirect": 0.131, "combined": 0.080}}
# 1 bounce (against 8-bounce Cycles): cornell 0.5022 / 0.2305, spot_room 0.7288 / 0.2723, courtyard 0.6849 / 0.4645
ONE = {"cornell": {"diffuse_indirect": 0.526, "combined": 0.242},
       "spot_room": {"diffuse_indirect": 0.756, "combined": 0.283},
       "courtyard": {"diffuse_indirect": 0.727, "combined": 0.493}}
TARGETS = {"diffuse_indirect": 0.20, "combined": 0.08}  # the issue's; all three scenes meet both


@pytest.fixture(scope="module")
def default(compare_examples):
    return compare_examples("committed", list(DEFAULT), "--method", "vct")


@pytest.fixture(scope="module")
def one(compare_examples):
    return compare_examples("committed", list(ONE), "--method", "vct", "--vct", "bounces=1")


@pytest.mark.parametrize("name", list(DEFAULT))
def test_vct_default_error_does_not_regress(default, name, check_bounds):
    check_bounds(default[name], DEFAULT[name])
    check_bounds(default[name], TARGETS)


@pytest.mark.parametrize("name", list(ONE))
def test_vct_one_bounce_error_does_not_regress(one, name, check_bounds):
    check_bounds(one[name], ONE[name])


def test_more_bounces_get_closer_to_full_bounce_cycles(default, one):
    """Cycles has 8 bounces; ours with 8 (extrapolated past 4) must be nearer on Diffuse Indirect than with 1 in
    every scene, by a wide margin (measured 0.50 → 0.10, 0.71 → 0.05, 0.69 → 0.09): if it were not, the bounces
    and their tail would not be adding the light they carry."""
    for name in DEFAULT:
        assert default[name]["rel_l1"]["diffuse_indirect"] < 0.7 * one[name]["rel_l1"]["diffuse_indirect"], name
