# SPDX-License-Identifier: GPL-3.0-or-later
"""LPV against Cycles on the typical interiors (issue: Light Propagation Volumes) — accuracy and regression bounds.

160×120, 32³ grid, against the committed Cycles references of examples/references/ (TRANSPORT: 4096 spp × 2 seeds,
8 bounces and 1 bounce, rendered by examples/references/make_references.py; the test never renders Cycles). Two
comparisons on each typical interior, as the issue asks: with full bounces (8 on both sides) and with the same single
bounce on both sides; for both transports.

The gathered transport — "transfer" (default, gpu_kernels/lpv/transfer.py: the gather from fixed clusters, cached)
and "gather" (gpu_kernels/lpv/gather.py, per bounce; measured before the transfer became the default) — meets the
issue's targets against full-bounce Cycles (Diffuse Indirect ≤ 25%, Combined ≤ 10%) on all three; they are asserted.

The propagating transport (the Kaplanyan–Dachsbacher face scheme, `transport=propagate`) is far from the targets:
the 2-band propagation is diffusive — a lobe pointing up keeps 0.096 of its flux going up per step — so light
from a lit floor turns sideways and returns to the floor; the one-bounce spot room has ~3× Cycles' indirect
light, nearly all on the spot-lit floor itself. Its bounds are regression bounds on today's level.

Bounds: the measured value + 2 × the reference's noise floor + 0.001, rounded up to 3 decimals (the rule of
test_examples_vs_cycles.py, whose docstring derives it: a reference rendered again moves our rel-L1 by about √2 × its
floor; 0.001 covers float16 storage and llvmpipe rounding). Our renderer is deterministic on one driver, so a change
of our output larger than that fails. A change that makes either transport better should lower these bounds.
"""
import pytest

SCENES = ("cornell", "spot_room", "courtyard")
# Measured 2026-12-05 against the 4096-spp references (rel-L1 Diffuse Indirect / Combined; noise floor DI / Combined):
# transfer, 8 bounces: cornell 0.0456 / 0.0273 (0.0114 / 0.0050), spot_room 0.0413 / 0.0161 (0.0127 / 0.0047),
# courtyard 0.0211 / 0.0191 (0.0202 / 0.0136); Σ ours / Σ Cycles of Diffuse Indirect 0.977 / 0.965 / 1.000.
# 2026-12-06 (stop 43, a floor under a closed box no longer in the receiver at the box's foot, lpv/wall_sides.py):
# cornell 0.0493 / 0.0292 (Σ 0.971: that floor had reflected as if lit), spot_room 0.0404 / 0.0157, courtyard
# 0.0213 / 0.0192; one bounce: cornell 0.0479 / 0.0225, spot_room 0.0501 / 0.0079, courtyard 0.0126 / 0.0142.
# Then clusters placed by their core (lpv/clusters.py _group): cornell 0.0489 / 0.0290, spot_room 0.0404 / 0.0158,
# courtyard 0.0213 / 0.0192.
GATHER_FULL = {"cornell": {"diffuse_indirect": 0.070, "combined": 0.039},
               "spot_room": {"diffuse_indirect": 0.068, "combined": 0.027},
               "courtyard": {"diffuse_indirect": 0.063, "combined": 0.048}}
# transfer, 1 bounce each side: cornell 0.0484 / 0.0227 (0.0050 / 0.0016), spot_room 0.0517 / 0.0081 (0.0032 /
# 0.0004), courtyard 0.0126 / 0.0142 (0.0060 / 0.0023).
GATHER_ONE_BOUNCE = {"cornell": {"diffuse_indirect": 0.060, "combined": 0.027},
                     "spot_room": {"diffuse_indirect": 0.060, "combined": 0.010},
                     "courtyard": {"diffuse_indirect": 0.026, "combined": 0.020}}
# propagate (ours 3 bounces, Cycles 8): cornell 0.6673 / 0.3151, spot_room 1.2466 / 0.4773, courtyard 1.0174 / 0.6896
PROPAGATE_FULL = {"cornell": {"diffuse_indirect": 0.692, "combined": 0.327},
                  "spot_room": {"diffuse_indirect": 1.273, "combined": 0.488},
                  "courtyard": {"diffuse_indirect": 1.059, "combined": 0.718}}
# propagate, 1 bounce each side: cornell 0.8741 / 0.2985, spot_room 2.9093 / 0.4434, courtyard 1.8230 / 0.7056
PROPAGATE_ONE_BOUNCE = {"cornell": {"diffuse_indirect": 0.886, "combined": 0.303},
                        "spot_room": {"diffuse_indirect": 2.917, "combined": 0.446},
                        "courtyard": {"diffuse_indirect": 1.837, "combined": 0.712}}
# Junction seams: pixels whose Diffuse Indirect is below 0.4 × the 5 × 5 mean of Cycles' around them
# (tests/support/compare_examples.py: dark_pixels). Before the lookup looked along the surface past corner voxels
# (lpv/lighting.glsl) every wall–floor junction showed a dark line: cornell 75, spot_room 141, courtyard 78 pixels
# against the 128-spp references; measured against the 4096-spp ones 3 / 1 / 0. The bound adds 10 pixels, about one
# junction's length in these 160 × 120 views: a seam that comes back along any one edge fails.
DARK_PIXELS = {"cornell": 3, "spot_room": 1, "courtyard": 0}
TARGETS = {"diffuse_indirect": 0.25, "combined": 0.10}  # the issue's, against full-bounce Cycles


@pytest.fixture(scope="module")
def gather_full(compare_examples):
    return compare_examples("committed", list(SCENES), "--method", "lpv")


@pytest.fixture(scope="module")
def gather_one_bounce(compare_examples):
    return compare_examples("committed", list(SCENES), "--method", "lpv", "--bounces", 1, "--lpv", "bounces=1")


@pytest.fixture(scope="module")
def propagate_full(compare_examples):
    return compare_examples("committed", list(SCENES), "--method", "lpv", "--lpv", "transport=propagate", "bounces=3")


@pytest.fixture(scope="module")
def propagate_one_bounce(compare_examples):
    return compare_examples("committed", list(SCENES), "--method", "lpv", "--bounces", 1,
                            "--lpv", "transport=propagate", "bounces=1")


@pytest.mark.parametrize("name", SCENES)
def test_gathered_lpv_full_bounce_error(gather_full, name, check_bounds):
    check_bounds(gather_full[name], GATHER_FULL[name])
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
