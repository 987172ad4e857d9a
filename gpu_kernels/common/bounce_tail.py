# SPDX-License-Identifier: GPL-3.0-or-later
"""The bounce tail both GI methods share: bounces K+1 … N estimated without gathering them.

The light added by successive bounces of a Jacobi (power) iteration tends to a fixed shape that shrinks by a fixed
ratio r per bounce (the dominant eigenvalue of the transport — in a white furnace of albedo ρ, exactly r = ρ). So
with B_k the flux bounce k added and r = B_K / B_(K−1) per RGB channel, the light of bounces K+1 … N is the last
increment's own spatial shape times Σ_{j=1}^{N−K} r^j — a geometric series truncated at the requested bounce count
like Cycles' bounce limit, not summed to infinity. The shaders apply it with common/bounce_tail.glsl.
"""
from __future__ import annotations

import numpy as np

MAX_RATIO = 0.99  # < 1: a passive scene cannot gain light per bounce


def tail_ratio(last, previous) -> np.ndarray:
    """r per RGB channel: the flux the last bounce added over the flux the one before added (0 where that was 0),
    clipped to [0, MAX_RATIO]."""
    last, previous = np.asarray(last, np.float64), np.asarray(previous, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(previous > 0, last / previous, 0.0)
    return np.clip(np.nan_to_num(ratio), 0.0, MAX_RATIO)


def tail_sum(ratio: np.ndarray, remaining: int) -> np.ndarray:
    """Σ_{j=1}^{remaining} r^j per channel: what multiplies the last increment to give bounces K+1 … N."""
    return ratio * (1.0 - ratio ** remaining) / (1.0 - ratio)
