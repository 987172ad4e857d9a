"""What `bounce-gi bench` writes: the Pareto front, speed-ups at equal error, a log-log plot (PNG) and summary.md.

Everything here works on the JSON report alone (no bpy, no GL), so a report can be re-plotted or summarised later.
"""
from __future__ import annotations

import glob
import math
import os

import numpy as np


def short_settings(method: str, s: dict) -> str:
    """The settings that tell the sweep's rows apart: grid resolution and bounces always, the other swept keys
    where they differ from the method's defaults."""
    from .bench import SWEPT_KEYS, default_settings

    default = default_settings(method)
    keys = [k for k in SWEPT_KEYS.get(method, ()) if k in s and
            (k in ("resolution", "bounces") or s[k] != default.get(k))]
    return " ".join(f"{k}={s[k]}" for k in keys)


def row_label(r: dict) -> str:
    return r["method"] + ("" if not r["settings"] else " " + short_settings(r["method"], r["settings"]))


def peer_label(p: dict) -> str:
    return p["engine"] + (f" {p['samples']} spp" if p["engine"] == "CYCLES" else "") + \
        (" + OIDN" if p["denoise"] else "")


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


def _fmt(x, spec=".4f"):
    return "—" if x is None else format(x, spec)


def _speedup_text(s: dict) -> str:
    if s["speedup"] is None:
        return "more accurate than any point measured" if s["how"] == "beyond" else "—"
    return ("≤ " if s["how"] == "at most" else "") + f"{s['speedup']:.2g}×"


def summary_markdown(report: dict) -> str:
    lines = ["# Bounce GI benchmark" + (" (--quick)" if report["quick"] else ""), "",
             f"Machine: {report.get('machine', {}).get('gl_renderer', 'unknown GL')}; "
             "times are median wall seconds per full frame (scene extraction + every pass re-run).", ""]
    for s in report["scenes"]:
        ref = s["reference"]
        front = {p["label"] for p in s["pareto"]}
        lines += [f"## {s['name']} ({s['resolution'][0]}x{s['resolution'][1]})", "",
                  f"Reference: Cycles {ref['samples']} spp x 2 seeds, {ref['bounces']} bounces; noise floor (rel-L1) "
                  f"Combined {_fmt(ref['noise_floor']['combined'])}, Diffuse Indirect "
                  f"{_fmt(ref['noise_floor']['diffuse_indirect'])}.", "",
                  "| renderer | settings | default | ms | rel-L1 Combined | rel-L1 Diff. Ind. | relMSE | FLIP | Pareto |",
                  "|---|---|---|---:|---:|---:|---:|---:|---|"]
        for r in s["rows"]:
            ms = None if r["seconds"] is None else r["seconds"] * 1000
            lines.append(f"| {r['method']} | {short_settings(r['method'], r['settings']) or '—'} | "
                         f"{'yes' if r['default'] else ''} | {_fmt(ms, '.1f')} | {_fmt(r['rel_l1']['combined'])} | "
                         f"{_fmt(r['rel_l1']['diffuse_indirect'])} | {_fmt(r['rel_mse'])} | {_fmt(r['flip'])} | "
                         f"{'*' if row_label(r) in front else ''}" + (f" error: {r['error']}" if "error" in r else "")
                         + " |")
        for p in s["peers"]:
            ms = None if p["seconds"] is None else p["seconds"] * 1000
            settings = (f"{p['samples']} spp" if p["samples"] else "defaults") + (" + OIDN" if p["denoise"] else "")
            lines.append(f"| {p['engine']} | {settings} | | {_fmt(ms, '.1f')} | {_fmt(p['rel_l1']['combined'])} | "
                         f"| | | {'*' if peer_label(p) in front else ''}" +
                         (f" {p['error']}" if "error" in p else "") + " |")
        lines += ["", "Speed-up at equal Combined error (Cycles time to reach our error ÷ our time; "
                      "log-log interpolation along the measured sample curve):", "",
                  "| ours | ms | rel-L1 | vs Cycles | vs Cycles + OIDN |", "|---|---:|---:|---|---|"]
        for sp in s.get("speedups", []):
            lines.append(f"| {sp['label']}{' (default)' if sp['default'] else ''} | {sp['seconds'] * 1000:.1f} | "
                         f"{sp['rel_l1']:.4f} | {_speedup_text(sp['cycles'])} | {_speedup_text(sp['cycles_oidn'])} |")
        lines += [""] + [f"- warning: {w}" for w in s["warnings"]] + [""]
    lines += [f"Plots: {', '.join(os.path.basename(p) for p in report['plots'])}", ""]
    return "\n".join(lines)


# ---- plot: numpy + OpenImageIO only (no matplotlib in the dependency list) ----

PLOT_W, PLOT_H, MARGIN = 860, 520, (80, 170, 40, 60)  # left, right (the legend), top, bottom
COLOURS = {"none": (0.45, 0.45, 0.45), "lpv": (0.1, 0.45, 0.85), "vct": (0.55, 0.2, 0.75), "front": (0.0, 0.0, 0.0),
           "cycles": (0.85, 0.35, 0.1), "cycles_oidn": (0.1, 0.65, 0.3), "eevee": (0.85, 0.1, 0.45)}


def _font():
    found = glob.glob("/usr/share/fonts/**/DejaVuSans.ttf", recursive=True) + \
        glob.glob("/usr/share/fonts/**/*.ttf", recursive=True)
    return found[0] if found else None


class _Canvas:
    def __init__(self, xs, ys):
        self.img = np.ones((PLOT_H, PLOT_W, 3), np.float32)
        lx, ly = np.log10(xs), np.log10(ys)
        self.x0, self.x1 = math.floor(lx.min() - 0.1), math.ceil(lx.max() + 0.1)
        self.y0, self.y1 = math.floor(ly.min() - 0.1), math.ceil(ly.max() + 0.1)
        self._yy, self._xx = np.mgrid[0:PLOT_H, 0:PLOT_W]

    def to_px(self, x, y):
        left, right, top, bottom = MARGIN
        u = (math.log10(x) - self.x0) / (self.x1 - self.x0)
        v = (math.log10(y) - self.y0) / (self.y1 - self.y0)
        return left + u * (PLOT_W - left - right), PLOT_H - bottom - v * (PLOT_H - top - bottom)

    def dot(self, px, py, colour, r=4, hollow=False):
        d = np.hypot(self._xx - px, self._yy - py)
        self.img[(d <= r) & ((d >= r - 1.5) if hollow else True)] = colour

    def line(self, a, b, colour, width=1.5):
        n = int(max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 2) + 2
        for t in np.linspace(0, 1, n):
            x, y = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
            x0, x1 = int(max(0, x - width / 2)), int(min(PLOT_W, x + width / 2 + 1))
            y0, y1 = int(max(0, y - width / 2)), int(min(PLOT_H, y + width / 2 + 1))
            self.img[y0:y1, x0:x1] = colour


def write_plot(path: str, entry: dict) -> None:
    """Log-log time vs Combined rel-L1: our rows by method, our Pareto front, Cycles ± OIDN curves, EEVEE."""
    import OpenImageIO as oiio

    from ..gpu_kernels.output import exr as exr_io

    ok = lambda p: p.get("seconds") and p["rel_l1"].get("combined")  # noqa: E731
    rows = [r for r in entry["rows"] if ok(r)]
    peers = [p for p in entry["peers"] if ok(p)]
    pts = [(p["seconds"], p["rel_l1"]["combined"]) for p in rows + peers]
    if not pts:
        raise ValueError("no point with both a time and an error")
    c = _Canvas(np.array([p[0] for p in pts]), np.array([p[1] for p in pts]))
    left, right, top, bottom = MARGIN
    grey = (0.85, 0.85, 0.85)
    for e in range(c.x0, c.x1 + 1):
        c.line(c.to_px(10.0 ** e, 10.0 ** c.y0), c.to_px(10.0 ** e, 10.0 ** c.y1), grey, 1)
    for e in range(c.y0, c.y1 + 1):
        c.line(c.to_px(10.0 ** c.x0, 10.0 ** e), c.to_px(10.0 ** c.x1, 10.0 ** e), grey, 1)
    for denoise, key in ((False, "cycles"), (True, "cycles_oidn")):
        curve = [(p["seconds"], p["rel_l1"]["combined"]) for p in sorted(peers, key=lambda p: p["samples"] or 0)
                 if p["engine"] == "CYCLES" and p["denoise"] == denoise]  # in sample order
        for a, b in zip(curve, curve[1:]):
            c.line(c.to_px(*a), c.to_px(*b), COLOURS[key])
        for p in curve:
            c.dot(*c.to_px(*p), COLOURS[key], 4)
    for p in peers:
        if p["engine"] != "CYCLES":
            c.dot(*c.to_px(p["seconds"], p["rel_l1"]["combined"]), COLOURS["eevee"], 6)
    front = sorted((p["seconds"], p["rel_l1"]) for p in pareto(rows, []))
    for a, b in zip(front, front[1:]):
        c.line(c.to_px(*a), c.to_px(*b), COLOURS["front"], 1)
    for r in rows:
        c.dot(*c.to_px(r["seconds"], r["rel_l1"]["combined"]), COLOURS[r["method"]], 5)
    for p in front:
        c.dot(*c.to_px(*p), COLOURS["front"], 8, hollow=True)
    c.line((left, top), (left, PLOT_H - bottom), (0, 0, 0), 1)
    c.line((left, PLOT_H - bottom), (PLOT_W - right, PLOT_H - bottom), (0, 0, 0), 1)
    buf = oiio.ImageBuf(oiio.ImageSpec(PLOT_W, PLOT_H, 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(0, PLOT_W, 0, PLOT_H, 0, 1, 0, 3), c.img)
    font = _font()
    if font:
        def text(x, y, s, col=(0, 0, 0), size=13):
            oiio.ImageBufAlgo.render_text(buf, int(x), int(y), s, size, font, col)
        for e in range(c.x0, c.x1 + 1):
            text(c.to_px(10.0 ** e, 1)[0] - 14, PLOT_H - bottom + 18, f"1e{e}")
        for e in range(c.y0, c.y1 + 1):
            text(left - 44, c.to_px(1, 10.0 ** e)[1] + 4, f"1e{e}")
        text(PLOT_W / 2 - 60, PLOT_H - 12, "seconds per frame")
        text(8, top - 14, f"{entry['name']} {entry['resolution'][0]}x{entry['resolution'][1]}: Combined rel-L1")
        legend = [("none", "none"), ("lpv", "lpv"), ("vct", "vct"), ("front", "our Pareto front"),
                  ("cycles", "Cycles"), ("cycles_oidn", "Cycles + OIDN"), ("eevee", "EEVEE")]
        for i, (key, name) in enumerate(legend):
            text(PLOT_W - right + 14, top + 16 + 16 * i, "● " + name, COLOURS[key])
    exr_io.write_png(path, (np.clip(buf.get_pixels(oiio.FLOAT), 0, 1) * 255 + 0.5).astype(np.uint8))
