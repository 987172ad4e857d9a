# SPDX-License-Identifier: GPL-3.0-or-later
"""What a benchmarked scene's rows and peers mean together: the Pareto front in (seconds, Combined rel-L1) and the
speed-up of each of our rows over Cycles (± OIDN) at equal error. Pure functions of the JSON report."""
from __future__ import annotations

import math

from .sweep import peer_label, row_label


def pareto(rows: list, peers: list) -> list:
    """Rows and peers not dominated in (seconds, Combined rel-L1), sorted by time."""
    points = [{"kind": "ours", "label": row_label(r), "method": r["method"], "settings": r["settings"],
               "seconds": r["seconds"], "rel_l1": r["rel_l1"]["combined"]} for r in rows]
    points += [{"kind": "peer", "label": peer_label(p), "engine": p["engine"], "samples": p["samples"],
                "denoise": p["denoise"], "seconds": p["seconds"], "rel_l1": p["rel_l1"]["combined"]} for p in peers]
    valid = [p for p in points if p["seconds"] is not None and p["rel_l1"] is not None]
    front = [p for p in valid if not any(q["seconds"] <= p["seconds"] and q["rel_l1"] <= p["rel_l1"] and
                                         (q["seconds"] < p["seconds"] or q["rel_l1"] < p["rel_l1"]) for q in valid)]
    return sorted(front, key=lambda p: p["seconds"])


def peer_time_at_error(peers: list, error: float, denoise: bool) -> tuple:
    """Seconds Cycles (± OIDN) needs to reach `error` (Combined rel-L1): log-log interpolation along its measured
    sample curve. Returns (seconds or None, how): 'interpolated', 'at most' (our error is above the curve's first
    point, so Cycles is at least that fast) or 'beyond' (more accurate than any Cycles point measured)."""
    curve = sorted(((p["seconds"], p["rel_l1"]["combined"]) for p in peers if p["engine"] == "CYCLES" and
                    p["denoise"] == denoise and p["seconds"] and p["rel_l1"]["combined"]), key=lambda c: c[0])
    if not curve:
        return None, "no curve"
    # The error of a sample curve should fall with time; take its running minimum so noise cannot make it rise.
    best, mono = math.inf, []
    for t, e in curve:
        best = min(best, e)
        mono.append((t, best))
    if error >= mono[0][1]:
        return mono[0][0], "at most"
    for (t0, e0), (t1, e1) in zip(mono, mono[1:]):
        if e1 <= error <= e0:
            if e0 == e1:
                return t0, "interpolated"
            a = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + a * (math.log(t1) - math.log(t0))), "interpolated"
    return None, "beyond"


def speedups(entry: dict) -> list:
    """Per row of ours: Cycles (and Cycles + OIDN) time to the same Combined error, divided by our time."""
    out = []
    for r in entry["rows"]:
        err, ours = r["rel_l1"]["combined"], r["seconds"]
        if err is None or not ours:
            continue
        item = {"label": row_label(r), "default": r["default"], "seconds": ours, "rel_l1": err}
        for denoise, key in ((False, "cycles"), (True, "cycles_oidn")):
            t, how = peer_time_at_error(entry["peers"], err, denoise)
            item[key] = {"seconds": t, "how": how, "speedup": None if t is None else t / ours}
        out.append(item)
    return out
