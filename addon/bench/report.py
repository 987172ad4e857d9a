# SPDX-License-Identifier: GPL-3.0-or-later
"""What `bounce-gi bench` writes besides the plots (plot.py): summary.md, the plain-text output, and the quality
table automatic quality (addon/quality.py) chooses from.

Everything here works on the JSON report alone (no bpy, no GL), so a report can be re-summarised later.
"""
from __future__ import annotations

import os
import statistics

from .front import pareto
from .sweep import peer_label, row_label, short_settings


def fmt(x, spec=".4f"):
    return "—" if x is None else format(x, spec)


def speedup_text(s: dict) -> str:
    if s["speedup"] is None:
        return "more accurate than any point measured" if s["how"] == "beyond" else "—"
    return ("≤ " if s["how"] == "at most" else "") + f"{s['speedup']:.2g}×"


def scene_table(s: dict) -> list:
    """summary.md's table of one scene: our rows, then the peers; '*' marks the Pareto front."""
    front = {p["label"] for p in s["pareto"]}
    lines = ["| renderer | settings | default | ms | rel-L1 Combined | rel-L1 Diff. Ind. | relMSE | FLIP | Pareto |",
             "|---|---|---|---:|---:|---:|---:|---:|---|"]
    for r in s["rows"]:
        ms = None if r["seconds"] is None else r["seconds"] * 1000
        lines.append(f"| {r['method']} | {short_settings(r['method'], r['settings']) or '—'} | "
                     f"{'yes' if r['default'] else ''} | {fmt(ms, '.1f')} | {fmt(r['rel_l1']['combined'])} | "
                     f"{fmt(r['rel_l1']['diffuse_indirect'])} | {fmt(r['rel_mse'])} | {fmt(r['flip'])} | "
                     f"{'*' if row_label(r) in front else ''}" + (f" error: {r['error']}" if "error" in r else "")
                     + " |")
    for p in s["peers"]:
        ms = None if p["seconds"] is None else p["seconds"] * 1000
        settings = (f"{p['samples']} spp" if p["samples"] else "defaults") + (" + OIDN" if p["denoise"] else "")
        lines.append(f"| {p['engine']} | {settings} | | {fmt(ms, '.1f')} | {fmt(p['rel_l1']['combined'])} | "
                     f"| | | {'*' if peer_label(p) in front else ''}" +
                     (f" {p['error']}" if "error" in p else "") + " |")
    return lines


def summary_markdown(report: dict) -> str:
    lines = ["# Bounce GI benchmark" + (" (--quick)" if report["quick"] else ""), "",
             f"Machine: {report.get('machine', {}).get('gl_renderer', 'unknown GL')}; "
             "times are median wall seconds per full frame (scene extraction + every pass re-run).", ""]
    for s in report["scenes"]:
        ref = s["reference"]
        lines += [f"## {s['name']} ({s['resolution'][0]}x{s['resolution'][1]})", "",
                  f"Reference: Cycles {ref['samples']} spp x 2 seeds, {ref['bounces']} bounces; noise floor (rel-L1) "
                  f"Combined {fmt(ref['noise_floor']['combined'])}, Diffuse Indirect "
                  f"{fmt(ref['noise_floor']['diffuse_indirect'])}.", ""]
        lines += scene_table(s)
        lines += ["", "Speed-up at equal Combined error (Cycles time to reach our error ÷ our time; "
                      "log-log interpolation along the measured sample curve):", "",
                  "| ours | ms | rel-L1 | vs Cycles | vs Cycles + OIDN |", "|---|---:|---:|---|---|"]
        for sp in s.get("speedups", []):
            lines.append(f"| {sp['label']}{' (default)' if sp['default'] else ''} | {sp['seconds'] * 1000:.1f} | "
                         f"{sp['rel_l1']:.4f} | {speedup_text(sp['cycles'])} | {speedup_text(sp['cycles_oidn'])} |")
        lines += [""] + [f"- warning: {w}" for w in s["warnings"]] + [""]
    lines += [f"Plots: {', '.join(os.path.basename(p) for p in report['plots'])}", ""]
    return "\n".join(lines)


def quality_table(report: dict) -> dict:
    """Our settings over all benched scenes: median seconds and mean Combined rel-L1 per setting, and which lie on
    the Pareto front of those aggregates. Automatic quality (quality.py) chooses from this."""
    by_label = {}
    for s in report["scenes"]:
        for r in s["rows"]:
            if r["seconds"] is not None and r["rel_l1"]["combined"] is not None:
                by_label.setdefault(row_label(r), []).append(r)
    entries = []
    for label, rows in by_label.items():
        if len(rows) != len(report["scenes"]):
            continue  # failed on some scene: not a setting to recommend
        entries.append({"label": label, "method": rows[0]["method"], "settings": rows[0]["settings"],
                        "seconds": statistics.median(r["seconds"] for r in rows),
                        "rel_l1": statistics.fmean(r["rel_l1"]["combined"] for r in rows)})
    front = {p["label"] for p in pareto([{"method": e["method"], "settings": e["settings"], "seconds": e["seconds"],
                                          "rel_l1": {"combined": e["rel_l1"]}} for e in entries], [])}
    for e in entries:
        e["pareto"] = e["label"] in front
    return {"machine": report.get("machine", {}), "scenes": [s["name"] for s in report["scenes"]],
            "resolutions": [s["resolution"] for s in report["scenes"]], "quick": report["quick"],
            "entries": sorted(entries, key=lambda e: e["seconds"])}


def format_bench(report: dict) -> str:
    """Plain-text output: the summary table and where the files went."""
    return summary_markdown(report) + f"\nwrote {report['summary']}, {report['quality_table']}"
