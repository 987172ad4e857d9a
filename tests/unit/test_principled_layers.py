# SPDX-License-Identifier: GPL-3.0-or-later
"""The Principled layering model (gpu_kernels/common/principled.py) and its tables (common/ggx_tables.py)."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import ggx_tables, principled
from bounce_gi.gpu_kernels.scene import Material

MUS = np.linspace(0.0, 1.0, 11)


def principled_material(**kw):
    return Material("m", specular_layer=True, **kw)


def test_committed_tables_are_the_generators():
    """Spot entries of the committed file recomputed by the generator's own quadrature (the whole table takes
    half a minute): the data is what the script makes, not edited by hand."""
    t = ggx_tables.load()
    assert t["E"].shape == (32, 32) and t["E_avg"].shape == (32,)
    assert t["s_ior"].shape == (16, 16, 16) and t["s5"].shape == (16, 16)
    for j, i in ((31, 0), (10, 16), (3, 31)):  # (μ index, roughness index) on the 32-grid
        mu, r = ggx_tables.grid(32)[j], ggx_tables.grid(32)[i]
        assert t["E"][j, i] == pytest.approx(ggx_tables.lobe_moments(mu, r)[0], abs=1e-5)
    z = np.clip(np.arange(16) / 15, 1e-4, 0.99)
    eta = float(ggx_tables.ior_from_f0(z[5] ** 4))
    mu, r = ggx_tables.grid(16)[4], ggx_tables.grid(16)[8]
    m = ggx_tables.lobe_moments(mu, r, [eta])
    f0 = ggx_tables.f0_from_ior(eta)
    assert t["s_ior"][5, 4, 8] == pytest.approx((m[2] / m[0] - f0) / (1 - f0), abs=1e-5)
    assert t["s5"][4, 8] == pytest.approx(m[1] / m[0], abs=1e-5)


def test_smooth_lobe_is_the_fresnel_curve():
    """At roughness 0 the lobe is a mirror: E = 1 and s is the real Fresnel curve between F0 and 1."""
    t = ggx_tables.load()
    assert np.allclose(t["E"][:, 0], 1.0, atol=1e-3)
    eta = 1.5
    s = principled.lookup(t["s_ior"], 0.0, np.array([0.2, 0.5, 1.0]), np.sqrt(0.5 / 2.5))
    f0 = ggx_tables.f0_from_ior(eta)
    exact = (ggx_tables.fresnel_dielectric(np.array([0.2, 0.5, 1.0]), eta) - f0) / (1 - f0)
    assert np.allclose(s, exact, atol=0.02)  # the 16-point μ grid's linear interpolation


def test_lookup_interpolates_linearly_on_cyclesgrid():
    table = np.arange(12, dtype=np.float32).reshape(3, 4)  # 3 μ rows × 4 roughness columns
    assert principled.lookup(table, 0.0, 0.0) == 0.0
    assert principled.lookup(table, 1.0, 1.0) == 11.0
    assert principled.lookup(table, 0.5, 0.5) == pytest.approx(5.5)
    assert np.allclose(principled.lookup(table, 1.0 / 3.0, np.array([0.0, 0.5])), [1.0, 5.0])


@pytest.mark.parametrize("level, ior", [(0.0, 1.5), (0.5, 1.0), (0.0, 2.5)])
def test_no_specular_layer_leaves_base_colour(level, ior):
    """Specular IOR Level 0 (F0 × 0) or IOR 1 removes the dielectric layer: Diffuse Color is the base colour."""
    d, g, *_ = principled.layer_factors(principled_material(specular_ior_level=level, ior=ior), MUS)
    assert np.allclose(d, 1.0) and np.allclose(g, 0.0)


def test_energy_split_adds_up():
    """Diffuse share + dielectric glossy albedo ≤ 1 at every μ (the layering takes what the layer reflects), with
    the split moving to glossy at grazing angles and for larger F0."""
    for rough in (0.0, 0.5, 1.0):
        d15, g15, *_ = principled.layer_factors(principled_material(roughness=rough), MUS)
        d25, g25, *_ = principled.layer_factors(principled_material(roughness=rough, ior=2.5), MUS)
        assert np.all(d15[:, 0] + g15[:, 0] <= 1.0 + 1e-9)
        assert np.all(g25[1:, 0] > g15[1:, 0]) and np.all(d25[1:, 0] < d15[1:, 0])
        assert g15[1, 0] > g15[-1, 0]  # grazing reflects more
    assert principled.layer_factors(principled_material(roughness=0.0), np.array([1.0]))[1][0, 0] == \
        pytest.approx(0.04, abs=1e-3)  # F0 of IOR 1.5 at normal incidence


def test_metallic_and_transmission_scale_the_diffuse_base():
    d0 = principled.layer_factors(principled_material(), MUS)[0]
    d_half = principled.layer_factors(principled_material(metallic=0.5), MUS)[0]
    d_metal = principled.layer_factors(principled_material(metallic=1.0), MUS)[0]
    d_glass = principled.layer_factors(principled_material(transmission=0.25), MUS)[0]
    assert np.allclose(d_half, 0.5 * d0) and np.allclose(d_metal, 0.0) and np.allclose(d_glass, 0.75 * d0)


def test_coat_darkens_the_base_and_adds_glossy():
    d, g, *_ = principled.layer_factors(principled_material(), MUS)
    dc, gc, *_ = principled.layer_factors(principled_material(coat_weight=1.0), MUS)
    assert np.all(dc <= d) and np.all(gc >= g)


def test_metal_albedo_approaches_one_at_grazing():
    _, _, m, e, e_avg, s5, _ = principled.layer_factors(principled_material(metallic=1.0, roughness=0.0), MUS)
    a = principled.metal_albedo((0.9, 0.6, 0.3), m, e, e_avg, s5)
    assert np.allclose(a[-1], (0.9, 0.6, 0.3), atol=1e-3)  # F0 at normal incidence
    assert np.all(a[1] > a[-1])


def test_diffuse_bsdf_and_lut_layout():
    mats = [Material("diffuse"), principled_material(), principled_material(metallic=1.0)]
    lut = principled.material_lut(mats)
    assert lut.shape == (principled.ROWS_PER_MATERIAL * 3, principled.LUT_SAMPLES, 4)
    assert np.allclose(lut[0, :, :3], 1.0) and np.allclose(lut[1, :, :3], 0.0)  # Lambertian, no glossy
    assert np.allclose(principled.diffuse_mean(mats[0]), 1.0)
    assert 0.9 < principled.diffuse_mean(mats[1])[0] < 0.97


def _total_albedo(mat, base):
    scale, offset, _ = principled.transport_albedo(mat)
    return np.asarray(base, np.float64) * scale + offset


@pytest.mark.parametrize("roughness", (0.0, 0.5, 1.0))
@pytest.mark.parametrize("level", (0.0, 0.5, 1.0))
def test_transport_albedo_of_a_white_dielectric_is_one(roughness, level):
    """Cycles' layering gives the diffuse base what the specular layer leaves (weight 1 − A(μ)), so a white
    Principled dielectric reflects everything, whatever its roughness and Specular IOR Level: diffuse + glossy = 1
    at every μ, hence in the cosine-weighted mean (to the midpoint sums' rounding, 1e-9)."""
    mat = principled_material(base_color=(1.0, 1.0, 1.0), roughness=roughness, specular_ior_level=level)
    assert np.allclose(_total_albedo(mat, (1.0, 1.0, 1.0)), 1.0, atol=1e-9)


def test_transport_albedo_counts_the_glossy_layer():
    """A grey wall (Specular IOR Level 0.5, IOR 1.5: F0 = 4 %) reflects more than its diffuse share: the glossy
    layer's cosine-weighted albedo is at least F0 and at most Fresnel's hemispherical mean for η = 1.5 (about 9 %).
    With Specular IOR Level 0 there is no layer: the base colour, all of it diffuse."""
    mat = principled_material(base_color=(0.5, 0.5, 0.5), roughness=0.5)
    scale, offset, diffuse = principled.transport_albedo(mat)
    assert np.allclose(scale, diffuse) and 0.04 <= offset[0] <= principled.dielectric_fss(1.5)
    plain = principled_material(base_color=(0.5, 0.5, 0.5), roughness=0.5, specular_ior_level=0.0)
    assert np.allclose(_total_albedo(plain, (0.5, 0.5, 0.5)), 0.5, atol=1e-9)
    assert np.allclose(principled.transport_albedo(Material("diffuse"))[:2], ((1, 1, 1), (0, 0, 0)))


@pytest.mark.parametrize("roughness", (0.0, 0.3, 0.8))
def test_transport_albedo_of_a_metal_is_its_glossy_colour_averaged(roughness):
    """metallic 1: no diffuse share; the total is the metal's Glossy Color (principled.metal_albedo, the shader's
    twin) averaged over μ with the cosine weight, to the quadrature's resolution (64 vs 4096 midpoints: 1e-4)."""
    base = (0.9, 0.6, 0.3)
    mat = principled_material(base_color=base, roughness=roughness, metallic=1.0)
    mu = (np.arange(4096) + 0.5) / 4096
    _, _, m, e, e_avg, s5, _ = principled.layer_factors(mat, mu)
    expected = 2.0 * (principled.metal_albedo(base, m, e, e_avg, s5) * mu[:, None]).mean(axis=0)
    assert np.allclose(principled.transport_albedo(mat)[2], 0.0)
    assert np.allclose(_total_albedo(mat, base), expected, atol=1e-4)
