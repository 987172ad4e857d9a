# SPDX-License-Identifier: GPL-3.0-or-later
"""The GGX albedo tables Cycles' Principled BSDF reads, computed here by quadrature on Cycles' own grids.

Cycles precomputes (by Monte Carlo) and looks up, with linear interpolation, four tables of the single-scattering
GGX lobe (α = roughness², Smith height-correlated masking-shadowing, Walter et al., "Microfacet Models for
Refraction through Rough Surfaces", 2007; Heitz, "Understanding the Masking-Shadowing Function", 2014):

- `E` (32 × 32, roughness × μ): the directional albedo with Fresnel = 1;
- `E_avg` (32, roughness): its cosine-weighted average over μ, 2∫E(μ)μ dμ;
- `s_ior` (16 × 16 × 16, roughness × μ × z): where the lobe-averaged real dielectric Fresnel lies between F0 and 1,
  (E_F/E − F0)/(1 − F0), for the IOR with F0 = z⁴ (z = √((η−1)/(η+1)));
- `s5` (16 × 16, roughness × μ): the lobe average of the Schlick weight (1 − h·ω_i)⁵ (the metals' F82 model).

The layering model in common/principled.py combines them as Cycles does. This module only makes them: run
`python -m bounce_gi.gpu_kernels.common.ggx_tables` to rewrite `ggx_tables.npz` (a few minutes on two cores);
`load()` reads the committed file.
"""
from __future__ import annotations

import os
from functools import lru_cache

import numpy as np

TABLE_FILE = os.path.join(os.path.dirname(__file__), "ggx_tables.npz")


def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance of a dielectric interface (relative IOR eta > 0); 1 under total reflection."""
    c = np.abs(cos_i)
    g2 = eta * eta - 1.0 + c * c
    g = np.sqrt(np.maximum(g2, 0.0))
    a = (g - c) / np.maximum(g + c, 1e-30)
    b = (c * (g + c) - 1.0) / np.maximum(c * (g - c) + 1.0, 1e-30)
    return np.where(g2 > 0.0, 0.5 * a * a * (1.0 + b * b), 1.0)


def f0_from_ior(eta):
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def ior_from_f0(f0):
    r = np.sqrt(np.clip(f0, 0.0, 0.9999))
    return (1.0 + r) / (1.0 - r)


def _lambda(alpha2, mu):
    tan2 = np.maximum(1.0 / np.maximum(mu * mu, 1e-12) - 1.0, 0.0)
    return 0.5 * (np.sqrt(1.0 + alpha2 * tan2) - 1.0)


def lobe_moments(mu: float, roughness: float, etas=(), n_u: int = 256, n_phi: int = 128) -> np.ndarray:
    """[E, E·s5, E_F(η) for each η] of the GGX reflection lobe seen from μ: ∫ f cosθ_o dω_o with Fresnel 1, with
    the Schlick weight (1 − h·ω_i)⁵, and with the real dielectric Fresnel. Midpoint quadrature over microfacet
    normals distributed as D(h)·cosθ_h (tan²θ_h = α²u/(1−u)), so narrow lobes are resolved as well as wide ones."""
    alpha = max(roughness * roughness, 1e-8)
    a2 = alpha * alpha
    u = (np.arange(n_u) + 0.5) / n_u
    phi = (np.arange(n_phi) + 0.5) / n_phi * 2.0 * np.pi
    uu, pp = np.meshgrid(u, phi, indexing="ij")
    cos_h = 1.0 / np.sqrt(1.0 + a2 * uu / (1.0 - uu))
    sin_h = np.sqrt(np.maximum(1.0 - cos_h * cos_h, 0.0))
    wi = np.array([np.sqrt(max(1.0 - mu * mu, 0.0)), 0.0, mu])
    hx, hy, hz = sin_h * np.cos(pp), sin_h * np.sin(pp), cos_h
    h_i = hx * wi[0] + hz * wi[2]
    mu_o = 2.0 * h_i * hz - wi[2]
    ok = (mu_o > 0.0) & (h_i > 0.0)
    g2 = 1.0 / (1.0 + _lambda(a2, mu) + _lambda(a2, np.maximum(mu_o, 1e-9)))
    # f·cosθ_o dω_o = D G2 F (h·ω_i) / μ_i dω_h, and the quadrature's density is D cosθ_h.
    w = np.where(ok, g2 * h_i / (mu * cos_h), 0.0)
    out = [w.mean(), (w * (1.0 - np.clip(h_i, 0.0, 1.0)) ** 5).mean()]
    out += [(w * fresnel_dielectric(h_i, eta)).mean() for eta in etas]
    return np.array(out)


def grid(n: int) -> np.ndarray:
    """Cycles' table abscissae: x/(n−1), clamped away from 0."""
    return np.clip(np.arange(n) / (n - 1), 1e-4, 1.0)


def compute() -> dict:
    """All four tables on Cycles' grids (roughness along the last axis, as Cycles stores them)."""
    rough32, mu32 = grid(32), grid(32)
    e = np.array([[lobe_moments(mu, r)[0] for r in rough32] for mu in mu32])
    mus = (np.arange(256) + 0.5) / 256
    e_avg = np.array([2.0 * np.mean([lobe_moments(mu, r, n_u=96, n_phi=48)[0] * mu for mu in mus]) for r in rough32])
    z = np.clip(np.arange(16) / 15, 1e-4, 0.99)
    etas = ior_from_f0(z ** 4)
    f0 = f0_from_ior(etas)
    rough16, mu16 = grid(16), grid(16)
    s_ior = np.zeros((16, 16, 16))
    s5 = np.zeros((16, 16))
    for j, mu in enumerate(mu16):
        for i, r in enumerate(rough16):
            m = lobe_moments(mu, r, etas)
            s5[j, i] = m[1] / m[0]
            s_ior[:, j, i] = np.clip((m[2:] / m[0] - f0) / (1.0 - f0), 0.0, 1.0)
    return {"E": np.clip(e, 0, 1).astype(np.float32), "E_avg": np.clip(e_avg, 0, 1).astype(np.float32),
            "s_ior": s_ior.astype(np.float32), "s5": s5.astype(np.float32)}


@lru_cache(maxsize=1)
def load() -> dict:
    with np.load(TABLE_FILE) as data:
        return {k: data[k] for k in data.files}


if __name__ == "__main__":
    np.savez_compressed(TABLE_FILE, **compute())
    print("wrote", TABLE_FILE)
