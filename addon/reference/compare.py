# SPDX-License-Identifier: GPL-3.0-or-later
"""Our render against a two-seed Cycles reference: rel-L1 per pass beside the reference's own noise floor, relMSE,
how many pixels' Diffuse Color match, and the per-pixel relative error of Combined for a heat map. What
`bounce-gi compare` prints and the compare operator (ui/compare.py) shows."""
from __future__ import annotations

import numpy as np

from ...gpu_kernels.output import metrics

# (pass name, report key) of the passes whose rel-L1 is reported.
COMPARED = (("Combined", "combined"), ("Diffuse Direct", "diffuse_direct"), ("Diffuse Indirect", "diffuse_indirect"),
            ("Glossy Direct", "glossy_direct"), ("Glossy Indirect", "glossy_indirect"))
GLOSSY_KEYS = ("glossy_direct", "glossy_indirect")


def geometry_mask(ours: dict, ref_passes: dict) -> np.ndarray:
    """Pixels that hit geometry in both renders (design: errors are taken over those only)."""
    return (ours["Position"].any(axis=-1) | (ours["Depth"][..., 0] < 1e9)) & (ref_passes["Depth"][..., 0] < 1e9)


def compare_result(scene, result, ref, method: str, samples: int, bounces: int) -> tuple[dict, np.ndarray]:
    """(report, mask) for our RenderResult of `scene` against a cycles.Reference rendered at `samples` spp."""
    ours = result.passes
    mask = geometry_mask(ours, ref.passes)
    # A glossy pass Cycles leaves black (no glossy closure in view) has no relative error: left out.
    compared = [(name, key) for name, key in COMPARED if key not in GLOSSY_KEYS
                or (name in ref.passes and np.abs(ref.passes[name][mask]).sum() > 0)]
    errors = {key: metrics.rel_l1(ours[name], ref.passes[name], mask) for name, key in compared}
    floors = {key: ref.noise_floor(name, mask) for name, key in compared}
    col_diff = np.abs(ours["Diffuse Color"] - ref.passes["Diffuse Color"]).max(axis=-1)
    report = {
        "method": method,
        "resolution": list(scene.resolution),
        "rel_l1": errors,
        "noise_floor": floors,
        "rel_mse": metrics.rel_mse(ours["Combined"], ref.passes["Combined"], mask),
        "diffuse_color_match": float(np.mean(col_diff[mask] < 0.01)) if mask.any() else float("nan"),
        "seconds": {"ours": result.timings["total"], "cycles": ref.seconds, "cycles_cached": ref.cached},
        "passes": {k: v for k, v in result.timings.items() if k != "total"},
        "reference": {"samples": samples, "seeds": 2, "bounces": bounces},
        "warnings": list(result.warnings),
        "pixels_compared": int(mask.sum()),
        "info": result.info,
    }
    return report, mask


def error_map(result, ref, mask) -> np.ndarray:
    """(H, W) relative error of Combined per pixel, 0 off geometry (metrics.relative_error_map)."""
    return metrics.relative_error_map(result.passes["Combined"], ref.passes["Combined"]) * mask
