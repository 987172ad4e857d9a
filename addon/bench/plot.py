# SPDX-License-Identifier: GPL-3.0-or-later
"""The benchmark's plot of one scene: log-log seconds per frame against Combined rel-L1, our rows by method, the
Pareto front of our rows, the Cycles ± OIDN sample curves and EEVEE (a PNG of 860x520 pixels).

matplotlib (Agg, no display) is a bench-only dependency (`pip install bounce-gi[bench]`), imported inside
`write_plot`, so the CLI and everything else start without it. Works on the JSON report alone.
"""
from __future__ import annotations

from .front import pareto

WIDTH_PX, HEIGHT_PX, DPI = 860, 520, 100
MARGIN_PX = (100, 170, 40, 60)  # left, right (the legend), top, bottom
COLOURS = {"none": (0.45, 0.45, 0.45), "lpv": (0.1, 0.45, 0.85), "vct": (0.55, 0.2, 0.75), "front": (0.0, 0.0, 0.0),
           "cycles": (0.85, 0.35, 0.1), "cycles_oidn": (0.1, 0.65, 0.3), "eevee": (0.85, 0.1, 0.45)}
METHODS = ("none", "lpv", "vct")
LEGEND = ("none", "lpv", "vct", "our Pareto front", "Cycles", "Cycles + OIDN", "EEVEE")  # in this order


def plottable(p: dict) -> bool:
    """A row or peer with both a time and an error (a log axis cannot show zero or a missing value)."""
    return bool(p.get("seconds") and p["rel_l1"].get("combined"))


def new_axes():
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(WIDTH_PX / DPI, HEIGHT_PX / DPI), dpi=DPI, facecolor="white")
    FigureCanvasAgg(fig)
    left, right, top, bottom = MARGIN_PX
    fig.subplots_adjust(left=left / WIDTH_PX, right=1 - right / WIDTH_PX, top=1 - top / HEIGHT_PX,
                        bottom=bottom / HEIGHT_PX)
    ax = fig.add_subplot()
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.grid(True, which="major", color=(0.85, 0.85, 0.85), linewidth=0.8)
    ax.set_axisbelow(True)
    return fig, ax


def draw_peers(ax, peers: list) -> None:
    """Cycles without and with OIDN as curves in sample order; EEVEE as single points."""
    for denoise, key, name in ((False, "cycles", "Cycles"), (True, "cycles_oidn", "Cycles + OIDN")):
        curve = [(p["seconds"], p["rel_l1"]["combined"]) for p in sorted(peers, key=lambda p: p["samples"] or 0)
                 if p["engine"] == "CYCLES" and p["denoise"] == denoise]  # in sample order
        if curve:
            ax.plot(*zip(*curve), "-o", color=COLOURS[key], markersize=6, linewidth=1.2, label=name)
    eevee = [(p["seconds"], p["rel_l1"]["combined"]) for p in peers if p["engine"] != "CYCLES"]
    if eevee:
        ax.plot(*zip(*eevee), "o", color=COLOURS["eevee"], markersize=8, label="EEVEE")


def draw_ours(ax, rows: list) -> None:
    """Our rows coloured by method, and the Pareto front of our rows alone: a line through it, rings around it."""
    front = sorted((p["seconds"], p["rel_l1"]) for p in pareto(rows, []))
    if front:
        ax.plot(*zip(*front), "-", color=COLOURS["front"], linewidth=0.8, zorder=3)
    for method in METHODS:
        pts = [(r["seconds"], r["rel_l1"]["combined"]) for r in rows if r["method"] == method]
        if pts:
            ax.plot(*zip(*pts), "o", color=COLOURS[method], markersize=7, label=method, zorder=4)
    if front:
        ax.plot(*zip(*front), "o", markerfacecolor="none", markeredgecolor=COLOURS["front"], markersize=12,
                markeredgewidth=1.2, label="our Pareto front", zorder=5)


def write_plot(path: str, entry: dict) -> None:
    """Log-log time vs Combined rel-L1: our rows by method, our Pareto front, Cycles ± OIDN curves, EEVEE."""
    rows = [r for r in entry["rows"] if plottable(r)]
    peers = [p for p in entry["peers"] if plottable(p)]
    if not rows and not peers:
        raise ValueError("no point with both a time and an error")
    fig, ax = new_axes()
    draw_peers(ax, peers)
    draw_ours(ax, rows)
    ax.set_xlabel("seconds per frame")
    ax.set_ylabel("Combined rel-L1")
    ax.set_title(f"{entry['name']} {entry['resolution'][0]}x{entry['resolution'][1]}", loc="left", fontsize=11)
    handles = dict(zip(*reversed(ax.get_legend_handles_labels())))
    names = [n for n in LEGEND if n in handles]
    ax.legend([handles[n] for n in names], names, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
              frameon=False, fontsize=9)
    fig.savefig(path, dpi=DPI, format="png")
