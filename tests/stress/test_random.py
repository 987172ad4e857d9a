# SPDX-License-Identifier: GPL-3.0-or-later
"""Randomized scenes from a property-based generator (hypothesis): boxes of any size and place, any albedo and
emission, 0–3 lights of any type and power, the camera anywhere, every length at a scale of 10⁻³ … 10⁴; every
render sane (support/stress.check_sane). Derandomized (the same examples on every run, no example database written
into the checkout); --stress-full runs five times as many."""
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings as hsettings, strategies as st

from bounce_gi.gpu_kernels.scene import Material
from support.stress import LIGHT_PASSES, check_sane, light, settings
from support.synthetic import box_quads, quad_scene

EXAMPLES, FULL_EXAMPLES = 5, 25

coord = st.floats(-2.0, 2.0, allow_nan=False)
box = st.tuples(st.tuples(coord, coord, coord), st.tuples(st.floats(0.05, 3.0), st.floats(0.05, 3.0),
                                                          st.floats(0.05, 3.0)), st.booleans())
material = st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0),
                     st.one_of(st.just(0.0), st.floats(0.0, 5.0)))
lamp = st.tuples(st.sampled_from(("POINT", "SPOT", "SUN", "AREA")), st.floats(-3.0, 4.0),
                 st.tuples(coord, coord, coord))
scene_spec = st.fixed_dictionaries({
    "boxes": st.lists(box, min_size=1, max_size=4), "materials": st.lists(material, min_size=1, max_size=3),
    "lights": st.lists(lamp, max_size=3), "eye": st.tuples(coord, coord, coord),
    "target": st.tuples(coord, coord, coord), "scale": st.floats(-3.0, 4.0), "world": st.floats(0.0, 1.0)})


def build(spec):
    s = 10.0 ** spec["scale"]
    quads = []
    for i, (lo, size, inward) in enumerate(spec["boxes"]):
        lo = np.multiply(lo, s)
        quads += box_quads(lo, lo + np.multiply(size, s), i % len(spec["materials"]), inward=inward)
    mats = [Material(f"m{i}", (r, g, b), emission=(e, e, e)) for i, (r, g, b, e) in enumerate(spec["materials"])]
    lights = [light(kind, 10.0 ** power, at, s, name=f"l{i}") for i, (kind, power, at) in enumerate(spec["lights"])]
    eye, target = np.multiply(spec["eye"], s), np.multiply(spec["target"], s)
    if np.linalg.norm(eye - target) < 1e-3 * s:
        target = eye + np.array([s, 0.0, 0.0])
    scene = quad_scene(quads, mats, lights, eye, target, world=(spec["world"],) * 3)
    scene.camera.clip_start, scene.camera.clip_end = 1e-3 * s, 1e3 * s
    return scene


@pytest.mark.parametrize("method", ("none", "lpv", "vct"))
def test_random_scenes_render_sanely(engine, full, method):
    @hsettings(max_examples=FULL_EXAMPLES if full else EXAMPLES, deadline=None, database=None, derandomize=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(scene_spec)
    def check(spec):
        scene = build(spec)
        s = settings(method)
        check_sane(engine.render(scene, s), scene, s)

    check()


@pytest.mark.parametrize("method", ("lpv", "vct"))
def test_random_scenes_scale_with_light_power(engine, full, method):
    """Any random scene renders ×k brighter with every light ×k (and emission and world ×k): rel-L1 within the
    linearity tolerance of test_power.py."""
    from test_power import TOL

    @hsettings(max_examples=max(2, (FULL_EXAMPLES if full else EXAMPLES) // 3), deadline=None, database=None,
               derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(scene_spec, st.floats(-4.0, 6.0))
    def check(spec, k):
        k = 10.0 ** k
        bright = dict(spec, lights=[(t, p + math.log10(k), a) for t, p, a in spec["lights"]],
                      materials=[(r, g, b, e * k) for r, g, b, e in spec["materials"]], world=spec["world"] * k)
        s = settings(method)
        a = engine.render(build(spec), s).passes
        b = engine.render(build(bright), s).passes
        for name in LIGHT_PASSES[:3]:
            ref = a[name][..., :3].astype(np.float64) * k
            denom = np.abs(ref).sum()
            if denom > 0:
                err = np.abs(b[name][..., :3] - ref).sum() / denom
                print(f"random scene ×{k:.3g} {method} {name}: rel-L1 {err:.2e}")
                assert err <= TOL[method], name

    check()
