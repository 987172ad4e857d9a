# SPDX-License-Identifier: GPL-3.0-or-later
"""The rows a benchmark measures: each method's settings from its cheap corner to its most accurate, and the
labels the summary, the Pareto front and the quality table name rows and peers by."""
from __future__ import annotations

from dataclasses import asdict, replace

# The settings a sweep varies per method; the summary names rows by these.
SWEPT_KEYS = {"lpv": ("transport", "resolution", "cascades", "gather_vpls", "max_iterations", "bounces"),
              "vct": ("resolution", "diffuse_cones", "bounces", "gathered_bounces", "indirect_scale")}


def default_settings(method: str) -> dict:
    from ...gpu_kernels.lpv.settings import LpvSettings
    from ...gpu_kernels.vct.settings import VctSettings

    cls = {"lpv": LpvSettings, "vct": VctSettings}.get(method)
    return asdict(cls()) if cls else {}


def sweep(quick: bool, width: int, height: int) -> list:
    """(method, settings dict, RenderSettings, default) for every row; default = the settings `render` uses."""
    from ...gpu_kernels.lpv.settings import LpvSettings
    from ...gpu_kernels.settings import RenderSettings
    from ...gpu_kernels.vct.settings import VctSettings

    base = RenderSettings(width=width, height=height)
    rows = [("none", {}, replace(base, method="none"), True)]
    # LPV: the gathered transport (default) from its cheap corner (16³, 1 bounce) to twice the VPLs and three
    # cascades; the propagating transport at the 3 bounces it was measured with, and with 16 iterations.
    lpv = [dict(resolution=16, bounces=1), {}] if quick else [
        dict(resolution=16, bounces=1), dict(resolution=16), dict(resolution=32, bounces=1), {},
        dict(gather_vpls=1024), dict(cascades=3), dict(transport="propagate", bounces=3),
        dict(transport="propagate", bounces=3, max_iterations=16)]
    # VCT: the cheap corner (32³, 6 cones, 1 bounce), a fast multi-bounce point, the single bounce at 64³, the
    # default, every bounce gathered (what the extrapolated tail saves), 128³, and reduced-resolution tracing.
    vct = [dict(resolution=32, diffuse_cones=6, bounces=1), {}] if quick else [
        dict(resolution=32, diffuse_cones=6, bounces=1), dict(resolution=32, diffuse_cones=6, gathered_bounces=3),
        dict(diffuse_cones=6, bounces=1), {}, dict(gathered_bounces=0), dict(resolution=128, bounces=1),
        dict(indirect_scale=2), dict(indirect_scale=4)]
    for changes in lpv:
        s = replace(LpvSettings(), **changes)
        rows.append(("lpv", asdict(s), replace(base, method="lpv", lpv=s), s == LpvSettings()))
    for changes in vct:
        s = replace(VctSettings(), **changes)
        rows.append(("vct", asdict(s), replace(base, method="vct", vct=s), s == VctSettings()))
    return rows


def short_settings(method: str, s: dict) -> str:
    """The settings that tell the sweep's rows apart: grid resolution and bounces always, the other swept keys
    where they differ from the method's defaults."""
    default = default_settings(method)
    keys = [k for k in SWEPT_KEYS.get(method, ()) if k in s and
            (k in ("resolution", "bounces") or s[k] != default.get(k))]
    return " ".join(f"{k}={s[k]}" for k in keys)


def row_label(r: dict) -> str:
    return r["method"] + ("" if not r["settings"] else " " + short_settings(r["method"], r["settings"]))


def peer_label(p: dict) -> str:
    return p["engine"] + (f" {p['samples']} spp" if p["engine"] == "CYCLES" else "") + \
        (" + OIDN" if p["denoise"] else "")
