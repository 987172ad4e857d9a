# SPDX-License-Identifier: GPL-3.0-or-later
"""Voxel cone tracing on surfaces that are not aligned with the grid: a closed room turned off the axes and a closed
sphere. Their walls are staircases of partly covered voxels, the case the anisotropic volumes fit worst; the per-pixel
sub-rays must meet them (vct/crossing.glsl). Runs on Mesa llvmpipe at 32³ in a few seconds."""
import math

import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.stress import furnace, turned
from support.synthetic import sphere_scene


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _render(engine, scene, size=(40, 30), **kw):
    return engine.render(scene, RenderSettings("vct", *size, vct=VctSettings(**{"resolution": 32, "indirect_scale": 1, **kw})))


def test_a_room_turned_off_the_grid_keeps_its_light(engine):
    """The closed white furnace turned 30° about z, one bounce: Diffuse Indirect = Le exactly, and no cone may leave
    (AO is the share of the cones that left the grid). A tilted wall is a staircase of voxels, each covering part of
    a column; before vct/crossing.glsl read each surface's depth at both ends of a step and added the coverages of
    one step, the per-pixel cones stepped over such walls: measured 0.703 of the light with 25% of the cones out
    (axis-aligned: 0.977 / 2%). Now 0.876 / 7.2% at 32³; bounds 0.84 and 0.10 leave room for another driver's
    rounding, not for the leak to come back."""
    r = _render(engine, turned(furnace(1.0, 1.0), 30.0), bounces=1)
    hit = r.passes["Depth"][..., 0] < 1e9
    indirect = float(r.passes["Diffuse Indirect"][..., 0][hit].mean())
    escaped = float(r.passes["AO"][..., 0][hit].mean())
    print(f"furnace turned 30°: Diffuse Indirect {indirect:.3f} of Le, cones out of the grid {escaped:.3f}")
    assert indirect >= 0.84 and escaped <= 0.10


@pytest.mark.parametrize("degrees, least", [(20.0, 0.76), (30.0, 0.69)])
def test_a_turned_room_keeps_its_light_over_many_bounces(engine, degrees, least):
    """The closed furnace of albedo 0.8 turned off the axes, 8 bounces: Diffuse Indirect = Le·Σ_{j=1..8} 0.8^j
    exactly. The bounces after the first are gathered at the voxels by the volumetric march (trace_cone), which
    composites each voxel of a tilted wall's staircase as an independent layer; neighbours along a column cover
    complementary parts of it, so their coverages must add (vct/inject.glsl column_area), or every gather loses
    light through the wall. Measured at 32³ with the column sum: 0.781 (20°) and 0.719 (30°) of the exact value;
    without it 0.735 and 0.619 (axis-aligned: 0.976). The bounds lie between the two."""
    rho = 0.8
    r = _render(engine, turned(furnace(rho, 1.0), degrees), bounces=8)
    hit = r.passes["Depth"][..., 0] < 1e9
    share = float(r.passes["Diffuse Indirect"][..., 0][hit].mean()) / sum(rho ** j for j in range(1, 9))
    print(f"furnace turned {degrees}°, 8 bounces: {share:.3f} of the exact value")
    assert share >= least


def test_a_closed_sphere_first_bounce_is_uniform_and_near_exact(engine):
    """Inside a closed sphere of albedo ρ lit by a point light of flux Φ at its centre, the one-bounce irradiance is
    E₁ = ρΦ/(4πR²) everywhere (every pair of points on a sphere has the same form factor). Curved walls are what
    the voxels' axis-aligned faces fit worst. Measured at 32³: mean 0.919·E₁, every pixel within 0.94–1.04 of the
    mean, 2.9% of the cones out of the grid (before the crossing test above: 0.554·E₁, 41% out). Bounds: mean in
    [0.88, 1.02], pixels within ±8% of it, at most 5% out."""
    r = engine.render(sphere_scene(subdivisions=4), RenderSettings("vct", 48, 36, vct=VctSettings(resolution=32,
                                                                                                   bounces=1)))
    e1 = 0.5 * 100.0 / (4 * math.pi)
    irradiance = r.passes["Diffuse Indirect"][..., 0] * math.pi / e1
    mean, escaped = float(irradiance.mean()), float(r.passes["AO"][..., 0].mean())
    print(f"sphere: mean E/E1 {mean:.3f}, min {irradiance.min():.3f}, max {irradiance.max():.3f}, out {escaped:.3f}")
    assert 0.88 <= mean <= 1.02 and escaped <= 0.05
    assert 0.92 * mean <= irradiance.min() and irradiance.max() <= 1.08 * mean
