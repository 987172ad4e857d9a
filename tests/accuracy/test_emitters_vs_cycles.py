# SPDX-License-Identifier: GPL-3.0-or-later
"""Rooms lit by emissive meshes only, against Cycles (issue 17: every emissive triangle shadowed, emission counted
once). Scenes from tests/support/emitter_scenes.py, 160×120, both methods' defaults, against Cycles 128 spp × 2 seeds
with 8 bounces:
- `lamp_room_albedo`: a furnished closed room lit by a closed, white (albedo 0.8) emissive lamp shade alone — the
  issue's case. Its inside is lit by its own emission and keeps that light in Cycles.
- `lamp_room_open`: the same room lit by a closed black shade and an open, bent two-sided emissive strip.

Measured (rel-L1 / Σ ours ÷ Σ Cycles; reference noise floor DD 0.024 / 0.022, DI 0.085 / 0.076):
                       Diffuse Direct     Diffuse Indirect LPV   Diffuse Indirect VCT
  lamp_room_albedo     0.033 / 1.004      0.139 / 0.881          0.139 / 0.884
  lamp_room_open       0.038 / 0.999      0.149 / 0.865          0.130 / 0.894 (+ see the report in the issue)
Before issue 17 (16 shadowed triangles; no trapped light): Diffuse Direct 0.63 / 1.63 and 0.44 / 1.44; Diffuse
Indirect LPV 0.472 / 1.458 and 0.435 / 0.565, VCT 1.898 / 2.897 (after the clustering alone; the unclustered
code was worse) and 0.324 / 1.321.

Tolerances:
- Diffuse Direct: Σ ours / Σ Cycles within 2% (the sum over 19 200 pixels carries almost none of the reference's
  noise; ours is the exact polygon integral, shadowed from sample points: measured within 0.4%), and rel-L1 ≤ 0.05:
  the references are noisy here (an exact render would score about the noise floor, 0.022–0.024), and what the
  shadow sample points cannot resolve — the strip's penumbra behind the cabinet — adds about 0.02 in quadrature.
- Diffuse Indirect, both methods: Σ ours / Σ Cycles in [0.75, 1.25] and rel-L1 ≤ 0.20 (noise floor ~0.08; the
  methods' own error of ~0.12 is that of their other scenes). The issue measured 4.4× (VCT) and 0.58× (LPV).
"""
import pytest

SCENES = ["tests.support.emitter_scenes:lamp_room_albedo", "tests.support.emitter_scenes:lamp_room_open"]
SAMPLES = 128
DIRECT_RATIO, DIRECT_REL_L1 = 0.02, 0.05
INDIRECT_RATIO, INDIRECT_REL_L1 = (0.75, 1.25), 0.20


@pytest.fixture(scope="module", params=["lpv", "vct"])
def results(request, compare_examples):
    return request.param, compare_examples(SAMPLES, SCENES, "--method", request.param)


@pytest.mark.parametrize("name", SCENES)
def test_emissive_meshes_light_directly_like_cycles(results, name):
    method, data = results
    r = data[name]
    assert r["noise_floor"]["diffuse_direct"] < 0.03, r["noise_floor"]  # else the bound below means little
    assert r["ratio"]["diffuse_direct"] == pytest.approx(1.0, abs=DIRECT_RATIO), (method, r["ratio"])
    assert r["rel_l1"]["diffuse_direct"] <= DIRECT_REL_L1, (method, r["rel_l1"], r["noise_floor"])


@pytest.mark.parametrize("name", SCENES)
def test_emission_bounces_once(results, name):
    method, data = results
    r = data[name]
    lo, hi = INDIRECT_RATIO
    assert lo <= r["ratio"]["diffuse_indirect"] <= hi, (method, r["ratio"])
    assert r["rel_l1"]["diffuse_indirect"] <= INDIRECT_REL_L1, (method, r["rel_l1"], r["noise_floor"])
