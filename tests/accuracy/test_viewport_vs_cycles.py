# SPDX-License-Identifier: GPL-3.0-or-later
"""What the viewport draws (`bounce-gi snapshot`: the surface atlas through Blender's gpu module) against Cycles,
like the render's accuracy tests, and against the render of the same view.

160×120, LPV at its defaults (32³, gathered transport, 8 bounces), atlases of 65 536 texels per page for the
direct light and 16 384 for the indirect (the viewport's final stage), against the committed 4096-spp × 2 seeds
Cycles references of examples/references/ (TRANSPORT, the ones test_lpv_vs_cycles.py uses). The viewport lights
surface points instead of pixels, so it differs from the render by what a texel cannot hold: shadow edges and
texture detail finer than a texel (the courtyard's sunlit patch has the longest edges), and Glossy Indirect, which
needs a view direction (none of these three scenes is glossy). Measured 2026-12-05 (Combined rel-L1, snapshot vs
Cycles / render vs Cycles / snapshot vs render): Cornell 0.0281 / 0.0273 / 0.0044, spot room 0.0181 / 0.0161 /
0.0038, courtyard 0.0276 / 0.0191 / 0.0183.

Bounds: against Cycles, the measured value + 2 × the reference's Combined noise floor (0.0050 / 0.0047 / 0.0136) +
0.001, rounded up (the rule of test_examples_vs_cycles.py). Against the render both sides are deterministic, and
the margin of 0.002 is only for the atlas layout rounding differently elsewhere.
"""
import pytest

SCENES = ("cornell", "spot_room", "courtyard")
SNAPSHOT_VS_CYCLES = {"cornell": 0.039, "spot_room": 0.029, "courtyard": 0.056}
SNAPSHOT_VS_RENDER = {"cornell": 0.0064, "spot_room": 0.0058, "courtyard": 0.0203}


@pytest.fixture(scope="module")
def reports(compare_examples):
    return compare_examples("committed", list(SCENES), "--method", "lpv", "--snapshot")


@pytest.mark.parametrize("name", SCENES)
def test_the_viewport_s_image_is_as_close_to_cycles_as_the_render(reports, name):
    errors = reports[name]["rel_l1"]
    print(name, errors)
    assert errors["snapshot_combined"] <= SNAPSHOT_VS_CYCLES[name]
    assert errors["snapshot_vs_render"] <= SNAPSHOT_VS_RENDER[name]
