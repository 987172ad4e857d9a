# SPDX-License-Identifier: GPL-3.0-or-later
"""Linearity in light power: every pass that is light must scale exactly with the lights' power, from 10⁻⁶ to 10⁹
W (sun: W/m²). Fixed-point sums (LPV injection, voxelisation) are scaled by a bound of the flux, so the same
digits survive at every power; a constant floor or clamp in watts would show here."""
import pytest

from support.stress import METHODS, box_room, check_sane, rel_l1, settings

POWERS = (1e-6, 1e-3, 1e3, 1e6, 1e9)
KINDS = ("POINT", "SUN", "SPOT", "AREA")
# rel-L1 of Combined / P against the P = 1 render (the issue asks for 1%). Direct light is float arithmetic:
# measured ≤ 9e-8, so 1e-6. The voxel methods sum in fixed point scaled by a bound of the flux, and a
# contribution's rounding to an integer step depends on the digits float32 gives it at each power: measured ≤ 3.6e-4
# (VCT, sun) and ≤ 7.1e-4 (LPV), so twice that — still 14× inside 1%, and a power-dependent clamp, floor or
# overflow moves the image by far more.
TOL = {"none": 1e-6, "vct": 8e-4, "lpv": 1.5e-3}
_reference = {}


def per_watt(engine, method, kind, power):
    scene = box_room(power=power, kind=kind)
    s = settings(method)
    result = engine.render(scene, s)
    check_sane(result, scene, s)
    return result.passes["Combined"][..., :3] / power


@pytest.mark.parametrize("method", ("none",) + METHODS)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("power", POWERS)
def test_light_scales_linearly_with_power(engine, method, kind, power):
    if (method, kind) not in _reference:
        # From a clean cache: an earlier module's view of the same room and light would lend the reference its
        # gathers (vct/reuse.py), and every power here is seen from one camera, so none of them would.
        engine.clear_cache()
        _reference[method, kind] = per_watt(engine, method, kind, 1.0)
    err = rel_l1(per_watt(engine, method, kind, power), _reference[method, kind])
    print(f"power {power:g} {kind} {method}: Combined/P rel-L1 {err:.2e}")
    assert err <= TOL[method]
