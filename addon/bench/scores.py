# SPDX-License-Identifier: GPL-3.0-or-later
"""The errors of one render against the two-seed Cycles reference, over pixels that hit geometry: rel-L1 and
relMSE (gpu_kernels/output/metrics.py) and FLIP of tone-mapped sRGB (flip-evaluator, in a subprocess)."""
from __future__ import annotations

import math
import os
import subprocess
import sys

# In a subprocess because flip-evaluator calls sys.exit on bad input.
FLIP_CODE = ("import sys, flip_evaluator as f; "
             "print('FLIP', float(f.evaluate(sys.argv[1], sys.argv[2], 'LDR', applyMagma=False)[1]))")


def finite(x):
    """float(x), or None for None, NaN and infinities (JSON-safe)."""
    return float(x) if x is not None and math.isfinite(float(x)) else None


def geometry_mask(ours: dict, ref: dict):
    return (ours["Position"].any(axis=-1) | (ours["Depth"][..., 0] < 1e9)) & (ref["Depth"][..., 0] < 1e9)


def flip_error(test_rgb, ref_rgb, tmp: str, python: str | None = None):
    """Mean FLIP of tone-mapped sRGB PNGs, computed in a subprocess; (value or None, warning or None).

    `python` runs the subprocess; None means sys.executable. The benchmark only ever runs from the `bounce-gi`
    console script (or `python -m bounce_gi.addon.cli`), where sys.executable is that venv's Python, which has
    flip-evaluator. Inside Blender sys.executable is the Blender binary, which cannot run `-c CODE`: a caller
    there would have to pass an interpreter explicitly (without one, FLIP comes back None with a warning)."""
    from ...gpu_kernels.output import exr as exr_io

    ref_png, test_png = os.path.join(tmp, "flip_ref.png"), os.path.join(tmp, "flip_test.png")
    try:
        exr_io.write_png(ref_png, exr_io.tonemap_srgb(ref_rgb))
        exr_io.write_png(test_png, exr_io.tonemap_srgb(test_rgb))
        proc = subprocess.run([python or sys.executable, "-c", FLIP_CODE, ref_png, test_png], capture_output=True,
                              text=True, timeout=300)
        for line in proc.stdout.splitlines():
            if line.startswith("FLIP "):
                return finite(float(line.split()[1])), None
        tail = (proc.stderr.strip().splitlines() or [f"exit code {proc.returncode}"])[-1]
        return None, f"FLIP failed: {tail}"
    except (OSError, subprocess.SubprocessError, ValueError) as exc:
        return None, f"FLIP failed: {exc}"


def score_row(out: dict, ours: dict, ref_passes: dict, tmp: str) -> None:
    """Fill a row's rel_l1 (Combined, Diffuse Indirect), rel_mse and flip; a FLIP failure becomes a warning."""
    from ...gpu_kernels.output import metrics

    mask = geometry_mask(ours, ref_passes)
    out["rel_l1"] = {"combined": finite(metrics.rel_l1(ours["Combined"], ref_passes["Combined"], mask)),
                     "diffuse_indirect": finite(metrics.rel_l1(ours["Diffuse Indirect"],
                                                               ref_passes["Diffuse Indirect"], mask))}
    out["rel_mse"] = finite(metrics.rel_mse(ours["Combined"], ref_passes["Combined"], mask))
    out["flip"], warning = flip_error(ours["Combined"], ref_passes["Combined"], tmp)
    if warning:
        out["warnings"].append(warning)
