# SPDX-License-Identifier: GPL-3.0-or-later
"""Principled BSDF against Cycles: Diffuse Color and Glossy Color over a sweep of its inputs, and Glossy Direct.

The sweep (tests/support/principled_sweep.py) is one sphere per combination of Specular IOR Level 0 / 0.25 / 0.5 /
1, IOR 1.0 / 1.33 / 1.5 / 2.5, roughness 0 / 0.5 / 1 and metallic 0 / 0.5 / 1 (144 spheres, base colour
(0.8, 0.45, 0.2)), seen from above, so every view angle μ appears. "Equal" is every channel within 0.01, the issue's
measure. Measured: on every sphere at least 99.5% of the pixels are equal for both passes (the rest lie on the
silhouette, μ → 0). Glossy Color is 2.5–5% lower than Cycles' at μ < 0.35 for roughness 0.5 (the albedo tables of
gpu_kernels/common/ggx_tables.py are our own quadrature of Cycles' definitions, not Cycles' numbers) — inside 0.01.

Glossy Direct (tests/support/glossy_direct.py, Cycles 64 spp × 2 seeds, no bounces, noise floor ≤ 0.007): rel-L1
measured 0.001–0.038 against point lights and rough area lights, 0.071–0.075 for a 0.5 m area light on a
roughness-0.2 floor (the polygon quadrature's 18 points alias a narrow lobe), 0.012–0.023 on the `principled`
stage under a sun, point, spot or area light.
"""
import pytest

EQUAL_TARGET = 0.98  # the issue's: Diffuse Color and Glossy Color equal on ≥ 98% of pixels, per combination
# Regression: measured ≥ 0.995 on every sphere; 0.99 lets two more silhouette pixels of ~370 differ.
EQUAL_BOUND = 0.99

GLOSSY_DIRECT_TARGET = 0.10  # the issue's
# measured rel-L1 of Glossy Direct; the bound adds 0.01: twice the largest noise floor (0.006, area light, roughness
# 0.2) for a different Cycles build or GL driver moving the seeded noise.
GLOSSY_DIRECT_MEASURED = {
    "floor-point-0.2-0": 0.0014, "floor-point-0.2-1": 0.0008, "floor-point-0.5-0": 0.0257,
    "floor-point-0.5-1": 0.0016, "floor-point-0.8-0": 0.0298, "floor-point-0.8-1": 0.0012,
    "floor-area-0.2-0": 0.0745, "floor-area-0.2-1": 0.0714, "floor-area-0.5-0": 0.0339, "floor-area-0.5-1": 0.0046,
    "floor-area-0.8-0": 0.0380, "floor-area-0.8-1": 0.0019,
    "stage-sun": 0.0155, "stage-point": 0.0125, "stage-spot": 0.0185, "stage-area": 0.0226,
}
MARGIN = 0.01


@pytest.fixture(scope="module")
def sweep(support_script):
    return support_script("principled_sweep.py", 4)


@pytest.fixture(scope="module")
def glossy_direct(support_script):
    return support_script("glossy_direct.py", 64)


@pytest.mark.parametrize("pass_key", ["diffuse", "glossy"])
def test_sweep_colours_equal_cycles(sweep, pass_key):
    assert len(sweep) == 144
    worst = min(sweep.items(), key=lambda kv: kv[1][pass_key])
    print(pass_key, "worst", worst)
    for combo, entry in sweep.items():
        assert entry[pass_key] >= EQUAL_TARGET, (combo, entry)
        assert entry[pass_key] >= EQUAL_BOUND, (combo, entry)


@pytest.mark.parametrize("case", sorted(GLOSSY_DIRECT_MEASURED))
def test_glossy_direct(glossy_direct, case):
    r = glossy_direct[case]
    print(case, r)
    assert r["rel_l1"] <= GLOSSY_DIRECT_TARGET, r
    assert r["rel_l1"] <= GLOSSY_DIRECT_MEASURED[case] + MARGIN, r
