# SPDX-License-Identifier: GPL-3.0-or-later
"""Cycles' Principled BSDF layering: how much of the base colour each closure gets, as a function of μ = n·ω_view.

Cycles builds the Principled BSDF top-down (kernel/svm/closure.h): coat, then metal, transmission, the dielectric
specular layer and the diffuse base. Each layer takes its directional albedo A(μ) from what lies below
(`closure_layering_weight`: weight × (1 − max over channels of A/weight)), and the Diffuse Color / Glossy Color
passes show the closures' weights times their albedo estimates (`bsdf_albedo`). For a GGX layer with Fresnel F the
estimate is mix(F0, 1, s(roughness, μ, η)) from a precomputed table (common/ggx_tables.py), times the multiscatter
"darkening" E + F_ms·(1 − E) of Kulla and Conty, "Revisiting Physically Based Shading at Imageworks" (2017), which
Cycles folds into the closure weight when the distribution is Multiscatter GGX (the default). Look-ups interpolate
the tables linearly on Cycles' own grids, so they land where Cycles' do.

Per material everything but the base colour is a function of μ alone, so `material_lut` tabulates it: five rows of
LUT_SAMPLES texels (μ = k/(LUT_SAMPLES−1)) per material, read by shaders/common/principled.glsl.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from . import ggx_tables
from .ggx_tables import f0_from_ior, fresnel_dielectric, ior_from_f0

LUT_SAMPLES = 65
ROWS_PER_MATERIAL = 5
MUS = np.linspace(0.0, 1.0, LUT_SAMPLES)


def lookup(table: np.ndarray, *coords) -> np.ndarray:
    """Cycles' lookup_table_read_2D/3D: coordinates in [0, 1] (fastest-varying axis first, as Cycles passes them),
    linear interpolation between the entries at x·(n−1)."""
    out = table.astype(np.float64)
    for axis, x in zip(range(table.ndim - 1, -1, -1), coords):
        n = table.shape[axis]
        t = np.clip(np.asarray(x, np.float64), 0.0, 1.0) * (n - 1)
        i = np.minimum(t.astype(int), n - 1)
        j = np.minimum(i + 1, n - 1)
        frac = t - i
        lo, hi = np.take(out, i, axis=axis), np.take(out, j, axis=axis)
        shape = [1] * lo.ndim
        if np.ndim(frac):
            shape[axis] = -1
        out = lo + (hi - lo) * np.reshape(frac, shape)
    return out


@lru_cache(maxsize=64)
def dielectric_fss(eta: float) -> float:
    """The cosine-weighted hemispherical average of the dielectric Fresnel reflectance, 2∫F(μ)μ dμ."""
    mu = (np.arange(512) + 0.5) / 512
    return float(2.0 * np.mean(fresnel_dielectric(mu, eta) * mu))


def _multiscatter_darkening(e, e_avg, fss):
    """E + F_ms·(1 − E): what Cycles' microfacet_ggx_preserve_energy leaves in a closure's weight (Kulla–Conty)."""
    fss = np.asarray(fss, np.float64)
    fms = fss * e_avg / (1.0 - fss * (1.0 - e_avg))
    return e[..., None] + fms * (1.0 - e[..., None])


def ggx_terms(roughness: float, mu: np.ndarray):
    """(E(μ), E_avg, s5(μ)) of Cycles' tables at this roughness."""
    t = ggx_tables.load()
    return (lookup(t["E"], roughness, mu), float(lookup(t["E_avg"], roughness)), lookup(t["s5"], roughness, mu))


def dielectric_albedo(mu, roughness, eta, tint=(1.0, 1.0, 1.0), multiscatter=True) -> np.ndarray:
    """(len(μ), 3): the albedo estimate of a GGX layer with Principled's dielectric Fresnel, F0 = F0(η) × tint."""
    mu = np.asarray(mu, np.float64)
    if eta < 1.0:
        eta = 1.0 / eta
    z = np.sqrt(abs((eta - 1.0) / (eta + 1.0)))
    s = lookup(ggx_tables.load()["s_ior"], roughness, mu, z)
    f0_real = f0_from_ior(eta)
    f0 = f0_real * np.asarray(tint, np.float64)
    albedo = f0 + (1.0 - f0) * s[:, None]
    if multiscatter:
        e, e_avg, _ = ggx_terms(roughness, mu)
        s_avg = np.clip((dielectric_fss(float(eta)) - f0_real) / (1.0 - f0_real), 0.0, 1.0)
        albedo = albedo * _multiscatter_darkening(e, e_avg, f0 + (1.0 - f0) * s_avg)
    return albedo


def specular_eta(ior: float, level: float) -> float:
    """Principled's Specular IOR Level: F0 scaled by 2·level, and the IOR that has that F0 (1: no specular layer)."""
    ior = max(float(ior), 1e-5)
    if level == 0.5:
        return ior
    eta = float(ior_from_f0(f0_from_ior(ior) * 2.0 * max(level, 0.0)))
    return 1.0 / eta if ior < 1.0 else eta


def layer_factors(mat, mu=MUS):
    """(D, G, M, E, E_avg, s5, layer) over μ for a Material: D (n, 3) multiplies the base colour into Diffuse Color;
    G (n, 3) is the glossy albedo of the coat and the dielectric layer; M (n, 3) the metallic closure's weight,
    whose albedo (it depends on the base colour, maybe a texture) the shader completes with E, E_avg and s5;
    `layer` what Glossy Direct needs of the dielectric layer's Fresnel: (F0 × tint (3), s(μ) (n), η, real F0)."""
    mu = np.asarray(mu, np.float64)
    n = len(mu)
    zeros = np.zeros((n, 3))
    if not mat.specular_layer:  # Diffuse BSDF, or a viewport-colour fallback: Lambertian, × (1 − metallic)
        return (np.full((n, 3), 1.0 - float(mat.metallic)), zeros, zeros, np.ones(n), 1.0, np.zeros(n),
                (np.zeros(3), np.zeros(n), 1.0, 0.0))
    metallic, transmission = float(np.clip(mat.metallic, 0, 1)), float(np.clip(mat.transmission, 0, 1))
    weight = np.ones((n, 3))
    glossy = np.zeros((n, 3))
    if mat.coat_weight > 0.0:
        coat_ior = max(float(mat.coat_ior), 1.0)
        coat = mat.coat_weight * dielectric_albedo(mu, mat.coat_roughness, coat_ior, multiscatter=mat.multiscatter)
        glossy += coat
        weight *= np.clip(1.0 - coat.max(axis=1), 0.0, 1.0)[:, None]
        tint = np.asarray(mat.coat_tint, np.float64)
        if not np.allclose(tint, 1.0):  # Beer's law along the refracted ray, as Cycles approximates it
            cos_t = np.sqrt(1.0 - (1.0 - mu * mu) / coat_ior ** 2)
            weight *= 1.0 + (np.maximum(tint, 1e-8)[None, :] ** (1.0 / cos_t[:, None]) - 1.0) * min(mat.coat_weight, 1.0)
    metal_weight = metallic * weight
    weight = weight * (1.0 - metallic) * (1.0 - transmission)
    eta = specular_eta(mat.ior, mat.specular_ior_level)
    layer = (np.zeros(3), np.zeros(n), 1.0, 0.0)
    if eta != 1.0:
        spec = dielectric_albedo(mu, mat.roughness, eta, mat.specular_tint, mat.multiscatter)
        glossy += weight * spec
        eta_up = eta if eta >= 1.0 else 1.0 / eta
        s = lookup(ggx_tables.load()["s_ior"], mat.roughness, mu, np.sqrt((eta_up - 1.0) / (eta_up + 1.0)))
        layer = (f0_from_ior(eta_up) * np.asarray(mat.specular_tint, np.float64), s, eta_up, f0_from_ior(eta_up))
        weight = weight * np.clip(1.0 - spec.max(axis=1), 0.0, 1.0)[:, None]
    e, e_avg, s5 = ggx_terms(mat.roughness, mu)
    if not mat.multiscatter:
        e = np.ones(n)  # no darkening: the shader's E + F_ms(1 − E) is then 1
    return weight, glossy, metal_weight, e, e_avg, s5, layer


def material_lut(materials) -> np.ndarray:
    """(ROWS_PER_MATERIAL · M, LUT_SAMPLES, 4) float32, per material: (D, E), (G, s5), (M, E_avg), (F0 × tint, s),
    (η, real F0, 0, 0) — shaders/common/principled.glsl names them."""
    rows = []
    for mat in materials:
        d, g, m, e, e_avg, s5, (f0, s, eta, f0_real) = layer_factors(mat)
        n = len(e)
        rows += [np.c_[d, e], np.c_[g, s5], np.c_[m, np.full(n, e_avg)], np.c_[np.tile(f0, (n, 1)), s],
                 np.tile((eta, f0_real, 0.0, 0.0), (n, 1))]
    if not rows:
        rows = [np.zeros((LUT_SAMPLES, 4))] * ROWS_PER_MATERIAL
    return np.asarray(rows, np.float32)


def metal_albedo(base, metal_weight, e, e_avg, s5) -> np.ndarray:
    """The metallic closure's Glossy Color (F82-tint with white tint): weight × darkening × mix(F0, 1, s5), F0 the
    base colour; numpy twin of principled_glossy in shaders/common/principled.glsl."""
    f0 = np.clip(np.asarray(base, np.float64), 0.0, 1.0)
    fss = f0 + (1.0 - f0) / 21.0
    return metal_weight * _multiscatter_darkening(np.atleast_1d(e), e_avg, fss) * (f0 + (1.0 - f0) * np.atleast_1d(s5)[:, None])


def diffuse_mean(mat) -> np.ndarray:
    """rgb: the cosine-weighted average over view directions of D, 2∫D(μ)μ dμ — the share of the base colour a
    surface reflects diffusely in all."""
    return transport_albedo(mat)[2]


def transport_albedo(mat) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(scale, offset, diffuse) rgb: what a surface reflects of the light reaching it, with no view direction (a
    voxel, a shadow-map texel), as base ⊙ scale + offset, cosine-weighted over directions (2∫…μ dμ); `diffuse` is
    the diffuse base's part of `scale` (diffuse_mean).

    The glossy closures count too: in Cycles the light a glossy layer reflects goes on to light other surfaces,
    and their Diffuse Indirect holds it (a wall's 4 % specular reflection, a metal's whole reflection). A voxel
    cannot keep the lobe's direction, so that flux leaves it diffusely; the energy, which is what the bounce
    series compounds, is kept. The metal's albedo mix(F0, 1, s5) is linear in F0 = the base colour but for the
    multiscatter darkening, evaluated at the material's own base colour (exact where no texture drives it)."""
    mu = (np.arange(64) + 0.5) / 64
    d, g, m, e, e_avg, s5, _ = layer_factors(mat, mu)
    w = 2.0 * mu[:, None] / len(mu)  # the cosine-weighted mean as a sum over the midpoints
    diffuse = (d * w).sum(axis=0)
    offset = (g * w).sum(axis=0)
    scale = diffuse.copy()
    if np.any(m > 0.0):
        f0 = np.clip(np.asarray(mat.base_color[:3], np.float64), 0.0, 1.0)
        dark = _multiscatter_darkening(e, e_avg, f0 + (1.0 - f0) / 21.0) * m
        scale = scale + (dark * (1.0 - s5)[:, None] * w).sum(axis=0)
        offset = offset + (dark * s5[:, None] * w).sum(axis=0)
    return scale, offset, diffuse


SHARE_TERMS = 8  # polynomial terms of the viewport's fitted diffuse share (share_polynomial)


def share_polynomial(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The diffuse share D(μ) of each material's table row (rows (M, S, ≥3): rgb D at μ = k/(S−1), as
    material_lut's row 0) fitted by least squares with a polynomial of SHARE_TERMS terms in t = 2μ − 1, so that
    the viewport evaluates a few multiply-adds per pixel instead of a texture lookup (llvmpipe pays every fragment
    instruction ~500 000 times a redraw, and its texture sampling is dozens of them). Returns the coefficients
    (M, 3, SHARE_TERMS) — per channel, of 1, t, t², … — and each material's largest deviation from its row (M,).
    t on [−1, 1] keeps the monomials well conditioned and the float32 sum free of cancellation."""
    rows = np.asarray(rows, np.float64)[..., :3]
    t = 2.0 * np.linspace(0.0, 1.0, rows.shape[1]) - 1.0
    basis = t[:, None] ** np.arange(SHARE_TERMS)[None, :]  # (S, terms)
    values = rows.transpose(1, 0, 2).reshape(rows.shape[1], -1)  # (S, M·3)
    coeffs, *_ = np.linalg.lstsq(basis, values, rcond=None)
    error = np.abs(basis @ coeffs - values).reshape(rows.shape[1], len(rows), 3).max(axis=(0, 2))
    return coeffs.T.reshape(len(rows), 3, SHARE_TERMS), error
