# SPDX-License-Identifier: GPL-3.0-or-later
"""The diffuse cone set: equal-solid-angle regions of the hemisphere (a cap and one or two rings), each cone's
axis, weight and aperture, and where the sub-rays of a cone go (Crassin et al. 2011, "Interactive Indirect
Illumination Using Voxel Cone Tracing", uses five cones; these tables generalise it to 5..31)."""
from __future__ import annotations

import math

import numpy as np

MAX_CONES = 32  # vct/common.glsl (cone_table makes at most 31)


def valid_cone_count(count) -> bool:
    try:
        ring_sizes(count)
        return True
    except (TypeError, ValueError):
        return False


def ring_sizes(count: int) -> list[int]:
    """Regions of the diffuse cone set, from the normal outward: [1, n − 1] for 5..9 cones (a cap and one ring),
    [1, m, 2m] for n = 1 + 3m, m = 4..10 (13, 16, … 31 cones: a cap and two rings, the outer one twice as many
    sectors so every region keeps about the same shape). Anything else is not a valid count."""
    n = int(count)
    if 5 <= n <= 9:
        return [1, n - 1]
    if (n - 1) % 3 == 0 and 4 <= (n - 1) // 3 <= (MAX_CONES - 1) // 3:
        return [1, (n - 1) // 3, 2 * (n - 1) // 3]
    raise ValueError(f"diffuse_cones {n}: must be 5..9, or 13, 16, 19, … {MAX_CONES - 1} (1 + 3m, two rings)")


def cone_table(count: int, aperture_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Diffuse cones: (unit directions (n, 3) in the normal's frame, z = normal; weights (n,); tan(half-angle) (n,)).

    The hemisphere is cut into n regions of equal solid angle 2π/n: a polar cap, then one or two rings
    (ring_sizes) each cut into m equal azimuthal sectors; the boundaries fall where the solid angle above them is
    a whole number of regions, 1 − cosθ_k = (regions so far)/n. Cone k stands for region k (ring [θa, θb], width
    Δφ = 2π/m):
      weight  w_k = ∫_region cosθ dω = Δφ·(sin²θb − sin²θa)/2; Σ w_k = π exactly, so a uniform radiance L gives
              E = Σ w_k·L = π·L, the exact cosine-weighted hemisphere integral;
      axis    the region's cosine-weighted mean direction: the normal for the cap; for a sector tilted by
              atan2(2·sin(Δφ/2)·(sin³θb − sin³θa), Δφ·(cos³θa − cos³θb)) from the normal (∫ sin²θ cosθ dθ and
              ∫ cos²θ sinθ dθ over the ring); the second ring is turned half a sector against the first;
      aperture half-angle of a cone of the region's solid angle, acos(1 − 1/n) (27.3° for 9 cones, 18.7° for 19),
              unless given.
    Why two rings are offered (measured, 64³, 160×120, against 2048-spp Cycles): in the volumetric march
    (trace_cone, which the bounce gathers still use) a cone's mip level is capped by its height above the surface it
    starts from, so a wide cone reads a footprint narrower than itself and over-weights what lies on its axis: 9
    cones of 27° gave Cornell one-bounce Diffuse Indirect rel-L1 0.23–0.27, 19 cones of 18.7° 0.16. The per-pixel
    sub-rays (vct/crossing.glsl) need no cap: 9 cones of 7 sub-rays give 0.100, 19 of 7 0.084 (VctSettings).
    """
    n = int(count)
    dirs, weights = [], []
    done, cos_a = 0, 1.0
    for ring, m in enumerate(ring_sizes(n)):
        done += m
        cos_b = 1.0 - done / n
        sin_a, sin_b = math.sqrt(max(0.0, 1.0 - cos_a * cos_a)), math.sqrt(max(0.0, 1.0 - cos_b * cos_b))
        dphi = 2.0 * math.pi / m
        weight = dphi * (sin_b ** 2 - sin_a ** 2) / 2.0
        if m == 1:
            dirs.append((0.0, 0.0, 1.0))
        else:
            tilt = math.atan2(2.0 * math.sin(dphi / 2.0) * (sin_b ** 3 - sin_a ** 3), dphi * (cos_a ** 3 - cos_b ** 3))
            turn = 0.5 * dphi if ring == 2 else 0.0
            dirs += [(math.sin(tilt) * math.cos(turn + k * dphi), math.sin(tilt) * math.sin(turn + k * dphi),
                      math.cos(tilt)) for k in range(m)]
        weights += [weight] * m
        cos_a = cos_b
    half = math.radians(aperture_deg) if aperture_deg > 0 else math.acos(1.0 - 1.0 / n)
    return np.array(dirs), np.array(weights), np.full(n, math.tan(half))


def subray_radius(count: int) -> float:
    """Where the sub-rays around a cone's axis go (vct/crossing.glsl), in units of tan(half-angle): cut the cone's
    disc into a central disc and a ring of count − 1 sectors, all of equal area (central radius r0 = 1/√count); a
    sub-ray goes through the centroid of its sector's radial extent, (2/3)(1 − r0³)/(1 − r0²) — 0.736 for 7."""
    if count <= 1:
        return 0.0
    r0 = 1.0 / math.sqrt(count)
    return (2.0 / 3.0) * (1.0 - r0 ** 3) / (1.0 - r0 ** 2)
