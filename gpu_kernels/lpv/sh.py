# SPDX-License-Identifier: GPL-3.0-or-later
"""Two-band spherical harmonics and the Kaplanyan–Dachsbacher face scheme as linear maps (Kaplanyan and
Dachsbacher 2010, "Cascaded Light Propagation Volumes for Real-Time Indirect Illumination": propagation)."""
from __future__ import annotations

import math

import numpy as np

# Solid angle of the far face of the next cell, seen from a cell centre, and of each of its four side faces;
# FAR_FACE + 4·SIDE_FACE = 2π/3 (the widely copied 0.4234413544 has a wrong digit).
FAR_FACE = 0.4006696846
SIDE_FACE = 0.4234313544
AXES = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))
SH_FLUX = 2.0 * math.sqrt(math.pi)  # flux of SH coefficients c: c0·2√π


def sh_basis(d) -> np.ndarray:
    x, y, z = d
    return np.array([0.282094792, -0.488602512 * y, 0.488602512 * z, -0.488602512 * x])


def sh_clamped_cosine(n) -> np.ndarray:
    x, y, z = n
    return np.array([0.886226925, -1.023326708 * y, 1.023326708 * z, -1.023326708 * x])


def transfer_matrices() -> tuple[np.ndarray, np.ndarray]:
    """The face scheme of lpv/propagate.glsl as linear maps, one per neighbour direction d (light travelling d):
    T_d = Σ_faces (lobe(face)/π) ⊗ Y(ω_face)·Δω_face (coefficients received), and the incident-flux row
    Σ_faces Y(ω_face)·Δω_face. Returns (6, 4, 4) and (6, 4) float32."""
    transfer = np.zeros((6, 4, 4))
    incident = np.zeros((6, 4))
    for n, d in enumerate(AXES):
        d = np.asarray(d, float)
        for f in AXES:
            f = np.asarray(f, float)
            if f @ d < -0.5:
                continue  # the face shared with the neighbour
            far = f @ d > 0.5
            w = d if far else (d + 0.5 * f) / np.linalg.norm(d + 0.5 * f)
            weight = sh_basis(w) * (FAR_FACE if far else SIDE_FACE)
            transfer[n] += np.outer(sh_clamped_cosine(f) / math.pi, weight)
            incident[n] += weight
    return transfer.astype(np.float32), incident.astype(np.float32)
