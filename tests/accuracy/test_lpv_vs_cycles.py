# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV against Cycles on the typical interiors (issue: Light Propagation Volumes) — accuracy and regression bounds.

160×120, 32³ grid, Cycles 128 spp × 2 seeds. Two comparisons on each typical interior, as the issue asks: with
full bounces (8 on both sides) and with the same single bounce on both sides; for both transports.

The gathered transport — "transfer" (default, gpu_kernels/lpv/transfer.py: the gather from fixed clusters, cached)
and "gather" (gpu_kernels/lpv/gather.py, per bounce; measured before the transfer became the default) — meets the
issue's targets (Diffuse Indirect ≤ 25%,
Combined ≤ 10% against full-bounce Cycles): against 2048-spp references (noise floor DI 0.025 / 0.018 / 0.031)
it measures 0.071 / 0.040, 0.088 / 0.034, 0.069 / 0.051 (Cornell, spot room, courtyard). Against the 128-spp
references held here the numbers below are higher by the references' own noise (DI noise floor ~0.07; the
courtyard's Combined floor is 0.08, so its 0.099 is mostly Cycles' noise). The bounds hold today's measured
errors × 1.05 + 0.05: the references are seeded (the same Cycles build renders the same noise), so the margin is
for a different Cycles build or GL driver moving the noise.

The propagating transport (the Kaplanyan–Dachsbacher face scheme, `transport=propagate`) is far from the targets:
the 2-band propagation is diffusive — a lobe pointing up keeps 0.096 of its flux going up per step — so light
from a lit floor turns sideways and returns to the floor; the one-bounce spot room has 2.9× Cycles' indirect
light, nearly all on the spot-lit floor itself. Its bounds are regression bounds on today's level.
A change that makes either worse fails here; one that makes it better should lower these bounds.
"""
import pytest

SCENES = ("cornell", "spot_room", "courtyard")
# measured, rel-L1 Diffuse Indirect / Combined (8 bounces), transfer with its near field as octagons (2026-12-05):
# cornell 0.084 / 0.044, spot_room 0.084 / 0.032, courtyard 0.118 / 0.084 (with the receivers per axis, 2026-12-03:
# 0.087 / 0.047, 0.087 / 0.033, 0.118 / 0.084; before them 0.107 / 0.056, 0.135 /
# 0.051, 0.134 / 0.095; gather, before the lattice's 1/3-cell phase: 0.108 / 0.055, 0.115 / 0.044,
# 0.140 / 0.099)
GATHER_FULL = {"cornell": {"diffuse_indirect": 0.17, "combined": 0.11},
               "spot_room": {"diffuse_indirect": 0.18, "combined": 0.10},
               "courtyard": {"diffuse_indirect": 0.20, "combined": 0.16}}
# measured (1 bounce each side), transfer (2026-12-05): cornell 0.076 / 0.033, spot_room 0.078 / 0.011, courtyard
# 0.082 / 0.041 (2026-12-03: 0.077 / 0.035, 0.082 / 0.012, 0.082 / 0.041; before the receivers per axis 0.083 /
# 0.037, 0.104 / 0.015, 0.088 / 0.043; gather, before the lattice's phase: 0.089 / 0.037, 0.072 / 0.010, 0.095 /
# 0.046)
GATHER_ONE_BOUNCE = {"cornell": {"diffuse_indirect": 0.15, "combined": 0.09},
                     "spot_room": {"diffuse_indirect": 0.13, "combined": 0.07},
                     "courtyard": {"diffuse_indirect": 0.15, "combined": 0.10}}
# propagate, measured (ours 3 bounces, Cycles 8; 2026-12-03): cornell 0.672 / 0.321, spot_room 1.247 / 0.478,
# courtyard 1.019 / 0.691
PROPAGATE_FULL = {"cornell": {"diffuse_indirect": 0.78, "combined": 0.40},
                  "spot_room": {"diffuse_indirect": 1.35, "combined": 0.55},
                  "courtyard": {"diffuse_indirect": 1.07, "combined": 0.74}}
# propagate, measured (1 bounce each side; 2026-12-03): cornell 0.875 / 0.303, spot_room 2.909 / 0.443, courtyard
# 1.823 / 0.706
PROPAGATE_ONE_BOUNCE = {"cornell": {"diffuse_indirect": 0.99, "combined": 0.38},
                        "spot_room": {"diffuse_indirect": 3.09, "combined": 0.52},
                        "courtyard": {"diffuse_indirect": 2.06, "combined": 0.83}}
# Junction seams: pixels whose Diffuse Indirect is below 0.4 × the 5 × 5 mean of Cycles' around them
# (tests/support/compare_examples.py: dark_pixels). Before the lookup looked along the surface past corner voxels
# (lpv/lighting.glsl) every wall–floor junction showed a dark line: cornell 75, spot_room 141, courtyard 78 pixels;
# measured since 6 / 18 / 10. The bound adds 10 pixels, about one junction's length in these 160 × 120 views: a
# seam that comes back along any one edge fails.
DARK_PIXELS = {"cornell": 6, "spot_room": 18, "courtyard": 10}
TARGETS = {"diffuse_indirect": 0.25, "combined": 0.10}  # the issue's, against 2048-spp Cycles (see above)


@pytest.fixture(scope="module")
def gather_full(compare_examples):
    return compare_examples(128, list(SCENES), "--method", "lpv")


@pytest.fixture(scope="module")
def gather_one_bounce(compare_examples):
    return compare_examples(128, list(SCENES), "--method", "lpv", "--bounces", 1, "--lpv", "bounces=1")


@pytest.fixture(scope="module")
def propagate_full(compare_examples):
    return compare_examples(128, list(SCENES), "--method", "lpv", "--lpv", "transport=propagate", "bounces=3")


@pytest.fixture(scope="module")
def propagate_one_bounce(compare_examples):
    return compare_examples(128, list(SCENES), "--method", "lpv", "--bounces", 1, "--lpv", "transport=propagate",
                            "bounces=1")


@pytest.mark.parametrize("name", SCENES)
def test_gathered_lpv_full_bounce_error(gather_full, name, check_bounds):
    check_bounds(gather_full[name], GATHER_FULL[name])
    if name != "courtyard":  # the courtyard's 128-spp Combined noise floor (0.08) leaves no room under 0.10
        check_bounds(gather_full[name], TARGETS)


@pytest.mark.parametrize("name", SCENES)
def test_no_dark_lines_at_junctions(gather_full, name):
    assert gather_full[name]["dark_pixels"] <= DARK_PIXELS[name] + 10, gather_full[name]["dark_pixels"]


@pytest.mark.parametrize("name", SCENES)
def test_gathered_lpv_one_bounce_error(gather_one_bounce, name, check_bounds):
    check_bounds(gather_one_bounce[name], GATHER_ONE_BOUNCE[name])


@pytest.mark.parametrize("name", SCENES)
def test_propagated_lpv_full_bounce_error_does_not_regress(propagate_full, name, check_bounds):
    check_bounds(propagate_full[name], PROPAGATE_FULL[name])


@pytest.mark.parametrize("name", SCENES)
def test_propagated_lpv_one_bounce_error_does_not_regress(propagate_one_bounce, name, check_bounds):
    check_bounds(propagate_one_bounce[name], PROPAGATE_ONE_BOUNCE[name])
