# SPDX-License-Identifier: GPL-3.0-or-later
"""Error metrics against a reference (defined in docs/conventions.md), over pixels that hit geometry."""
from __future__ import annotations

import numpy as np


def rel_l1(x: np.ndarray, ref: np.ndarray, mask: np.ndarray | None = None) -> float:
    """Σ|x − r| / Σ|r| over masked pixels and RGB channels."""
    x, ref = _rgb(x), _rgb(ref)
    if mask is not None:
        x, ref = x[mask], ref[mask]
    denom = float(np.abs(ref).sum())
    return float(np.abs(x - ref).sum()) / denom if denom > 0 else float("nan")


def rel_mse(x: np.ndarray, ref: np.ndarray, mask: np.ndarray | None = None, eps: float = 0.01) -> float:
    """mean((x − r)² / (r² + 0.01))."""
    x, ref = _rgb(x), _rgb(ref)
    if mask is not None:
        x, ref = x[mask], ref[mask]
    if x.size == 0:
        return float("nan")
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + eps)))


def relative_error_map(x: np.ndarray, ref: np.ndarray, eps: float = 0.01) -> np.ndarray:
    """Per-pixel |x − r| / (|r| + eps), averaged over RGB (for heat maps)."""
    return np.mean(np.abs(_rgb(x) - _rgb(ref)) / (np.abs(_rgb(ref)) + eps), axis=-1)


def heatmap_rgb8(err: np.ndarray, vmax: float = 0.5) -> np.ndarray:
    """Map relative error 0..vmax to a black→red→yellow→white ramp (uint8 RGB)."""
    t = np.clip(err / vmax, 0, 1)[..., None]
    r = np.clip(3 * t, 0, 1)
    g = np.clip(3 * t - 1, 0, 1)
    b = np.clip(3 * t - 2, 0, 1)
    return (np.concatenate([r, g, b], axis=-1) * 255 + 0.5).astype(np.uint8)


def _rgb(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, np.float64)
    return a[..., :3] if a.ndim == 3 and a.shape[-1] >= 3 else a
