# SPDX-License-Identifier: GPL-3.0-or-later
"""Rotation: the whole scene (geometry, light, camera) turned about the vertical must give the same image — the
voxel grids stay aligned with the world's axes, so a room that is not is a staircase of partly covered voxels.

Direct light has no voxel grid: turned 30° its image differs by 7·10⁻⁴ in rel-L1 (its shadow maps' texels fall
elsewhere on the turned walls); bound 0.002. The voxel methods do not turn as well yet: these tests hold today's
measured error of Diffuse Indirect (rel-L1 against the unturned room, and the ratio of their means) as regression
bounds, the room at 80 × 60 with each method's default grid (LPV 32³, VCT 64³) — the turned room's walls are what
users' rooms are.
Measured 2026-12-05 (the turned room / the unturned one, Diffuse Indirect):
  LPV: 10° 0.959 (rel-L1 0.042), 30° 0.961 (0.041) since 2026-12-06: the unturned room's floor–wall junction cells
       became axis planes (lpv/crossings.py) and its light rose 0.8%, the turned room's (whose walls do not face
       along the axes) did not move; 0.967 (0.035) and 0.969 (0.036) before. Before its transfer's near field took
       every planar cluster as the octagon it spans in its own plane (lpv/clusters.polygons; an axis plane's
       rectangle only, before): 10° 0.878 (0.122), 30° 0.863 (0.137);
  VCT: 10° 0.880 (0.120), 30° 0.634 (0.366). Before the VCT's sub-rays read surfaces' depth at both ends of a step
       (vct/crossing.glsl) its per-pixel cones lost up to 29% more of a turned room's light; what is left is mostly
       the bounce gathers (vct/bounce.glsl: 0.84 of the light kept per gathered bounce at 30°, 0.99 unturned).
Bounds: the measured rel-L1 + 0.02 and the measured ratio − 0.03 (llvmpipe renders the same image every run; the
margin is for another driver's rounding), so a change that turns the rooms worse fails, and one that fixes them
should tighten these numbers toward 0 and 1.
"""
import pytest

from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.stress import box_room, check_sane, rel_l1, turned

SIZE = (80, 60)
# (rel-L1 bound, lowest ratio of the means) per method and angle
BOUNDS = {("none", 30): (0.002, 0.998),
          ("lpv", 10): (0.062, 0.929), ("lpv", 30): (0.061, 0.931),
          ("vct", 10): (0.140, 0.850), ("vct", 30): (0.386, 0.604)}
_reference = {}


def render(engine, method, degrees):
    settings = RenderSettings(method, *SIZE, lpv=LpvSettings(), vct=VctSettings())
    scene = turned(box_room(), degrees)
    result = engine.render(scene, settings)
    check_sane(result, scene, settings)
    return result.passes


@pytest.mark.parametrize("method, degrees", sorted(BOUNDS))
def test_a_turned_room_renders_like_the_unturned_one(engine, method, degrees):
    if method not in _reference:
        _reference[method] = render(engine, method, 0.0)
    ref, got = _reference[method], render(engine, method, degrees)
    hit = (ref["Depth"][..., 0] < 1e9) & (got["Depth"][..., 0] < 1e9)
    pass_name = "Combined" if method == "none" else "Diffuse Indirect"
    a, b = got[pass_name][..., :3], ref[pass_name][..., :3]
    err = rel_l1(a[hit], b[hit])
    ratio = float(a[hit].sum() / b[hit].sum())
    print(f"turned {degrees}° {method}: {pass_name} rel-L1 {err:.4f}, ratio {ratio:.3f}")
    bound, lowest = BOUNDS[method, degrees]
    assert err <= bound and ratio >= lowest
