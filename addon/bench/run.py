# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi bench`: time and error of our methods against a two-seed Cycles reference, beside Cycles (± OIDN)
and EEVEE peers rendered in the same run at the same resolution (peers.py); Pareto front, speed-ups at equal error
(front.py), log-log plot (plot.py) and summary.md (report.py); the table automatic quality picks from (quality.py).

Rows (ours, sweep.py): a warm-up render (shader compilation, uploads), then the median of N full frames, each with
every pass cache cleared, plus the scene extraction time (an update in Blender extracts too, and the Cycles peers'
times include their scene sync) (timing.py). Errors over pixels that hit geometry (docs/conventions.md, Error metrics): rel-L1 of
Combined and Diffuse Indirect, relMSE of Combined, FLIP of Combined (tone-mapped sRGB; in a subprocess because
flip-evaluator calls sys.exit on bad input) (scores.py). A row that fails records "error" instead of ending the run.
"""
from __future__ import annotations

import json
import os
import tempfile
import traceback

from ..scene_io import check_blend_path, check_out_dir, load_scene, write_text_atomic
from .front import pareto, speedups
from .peers import render_peers
from .plot import write_plot
from .report import quality_table, summary_markdown
from .scores import finite, score_row
from .sweep import row_label, sweep
from .timing import machine_info, time_extraction, time_ours

QUICK_RES = (96, 72)
QUALITY_FILE = "quality_front.json"  # what the bench writes for automatic quality (quality.py reads it)


def bench_row(engine, scene, ref, row, repeats, extract_seconds, tmp, progress) -> dict:
    method, settings_dict, settings, default = row
    out = {"method": method, "settings": settings_dict, "default": default, "seconds": None, "passes": {},
           "rel_l1": {"combined": None, "diffuse_indirect": None}, "rel_mse": None, "flip": None, "warnings": []}
    progress(f"bench: {row_label(out)}")
    try:
        seconds, passes, result = time_ours(engine, scene, settings, repeats)
    except Exception as exc:  # noqa: BLE001 — one failing setting must not end the benchmark
        out["error"] = f"{type(exc).__name__}: {exc}"
        progress(f"bench: {row_label(out)} failed: {out['error']}")
        if os.environ.get("BOUNCE_GI_DEBUG"):
            traceback.print_exc()
        return out
    out.update(seconds=extract_seconds + seconds, passes={"extract": extract_seconds, **passes},
               warnings=list(result.warnings), info=result.info)
    score_row(out, result.passes, ref.passes, tmp)
    return out


def bench_scene(path, quick, res, tmp, progress, eevee=True) -> dict:
    from ...gpu_kernels.engine import get_engine
    from ..reference.cycles import ReferenceSettings, render_reference

    resolution = tuple(res) if res else (QUICK_RES if quick else None)
    scene = load_scene(path, resolution)
    width, height = scene.resolution
    ref_settings = ReferenceSettings(width, height, samples=64 if quick else 256)
    progress(f"bench: {os.path.basename(path)} at {width}x{height}")
    ref = render_reference(scene.content_hash(), ref_settings, progress=progress)
    ref_mask = ref.passes["Depth"][..., 0] < 1e9
    engine = get_engine()
    repeats = 1 if quick else 3
    extract_seconds = time_extraction(resolution, repeats)
    rows = [bench_row(engine, scene, ref, row, repeats, extract_seconds, tmp, progress)
            for row in sweep(quick, width, height)]
    peers, warnings = render_peers(ref, ref_mask, width, height, quick, progress, tmp, eevee)
    entry = {"scene": os.path.abspath(path), "name": os.path.splitext(os.path.basename(path))[0],
             "resolution": [width, height],
             "reference": {"samples": ref_settings.samples, "seeds": len(ref_settings.seeds),
                           "bounces": ref_settings.bounces, "seconds": ref.seconds, "cached": ref.cached,
                           "noise_floor": {"combined": finite(ref.noise_floor("Combined", ref_mask)),
                                           "diffuse_indirect": finite(ref.noise_floor("Diffuse Indirect",
                                                                                      ref_mask))}},
             "rows": rows, "peers": peers, "pareto": pareto(rows, peers), "warnings": warnings}
    entry["speedups"] = speedups(entry)
    return entry


def run_bench(scenes: list, quick: bool, res, out_dir: str | None, progress, eevee: bool = True) -> dict:
    """The whole benchmark: every scene, plots, summary.md and quality_front.json in out_dir; returns the report."""
    from ...gpu_kernels.engine import get_engine

    paths = [check_blend_path(p) for p in scenes]  # all bad input is reported before anything renders
    out_dir = check_out_dir(out_dir or "bounce-gi-bench")
    report = {"quick": quick, "out": out_dir, "machine": machine_info(get_engine()), "scenes": [], "plots": []}
    with tempfile.TemporaryDirectory(prefix="bounce-gi-bench-") as tmp:
        for path in paths:
            entry = bench_scene(path, quick, res, tmp, progress, eevee)
            report["scenes"].append(entry)
            plot = os.path.join(out_dir, f"{entry['name']}_time_vs_error.png")
            try:
                write_plot(plot, entry)
                report["plots"].append(plot)
            except Exception as exc:  # noqa: BLE001 — a plot is a convenience, the numbers are the result
                entry["warnings"].append(f"plot failed: {exc}")
    report["summary"] = os.path.join(out_dir, "summary.md")
    write_text_atomic(report["summary"], summary_markdown(report))
    report["quality_table"] = os.path.join(out_dir, QUALITY_FILE)
    write_text_atomic(report["quality_table"], json.dumps(quality_table(report), indent=1))
    write_text_atomic(os.path.join(out_dir, "bench.json"), json.dumps(report, indent=1, default=float))
    return report
