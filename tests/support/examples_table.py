# SPDX-License-Identifier: GPL-3.0-or-later
"""The example scenes like users' against their committed Cycles references: rel-L1 per scene x method x pass.

    python tests/support/examples_table.py [NAME ...] [--methods lpv vct] [--references DIR] [--json]

Renders each scene (examples.references.FRAMES, or the named ones) with each method's defaults, as `bounce-gi
render` does (the scene built by examples.scenes, extracted, rendered by addon/cli's render_ours), and compares every
pass with the committed reference (examples/references/, never rendered here) over the pixels that hit geometry in
both (addon/reference/compare.geometry_mask), with gpu_kernels/output/metrics.rel_l1. A pass our renderer does not
write counts as 1.0 (a full error). Prints the markdown table (with each pass's noise floor) and a suggested BOUNDS
dict for tests/accuracy/test_examples_vs_cycles.py: after a renderer change, run this and paste the dict there.
With --json: one line `RESULT {json}` (what the test reads), no table.

Bounds suggested (MARGIN_RULE): measured + 2 x the pass's noise floor + 0.001, rounded up to 3 decimals; the
issue's target instead where the measurement meets it but measured + margin would not; exactly 1.0 for a pass we
do not write, or write as 0 (its rel-L1 is 1 whatever the reference). Diffuse Color's share of
pixels within 0.01 of Cycles': measured - 2 x the share of pixels whose Diffuse Color differs between the two seeds
- 0.001, rounded down, or 0.98 (the target) where met.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, ROOT)

# The passes of the table: Cycles' (examples.references.PASSES), then the diffuse light (Direct + Indirect: Cycles
# counts the world's light as direct, as we do since the sky light; their sum is kept as a check of the total).
DERIVED = "Diffuse Light"
MATCH = "Diffuse Color match"  # share of hit pixels whose Diffuse Color is within 0.01 of Cycles' in every channel
MATCH_TOLERANCE = 0.01
METHODS = ("lpv", "vct")
# The issue's targets (rel-L1 against 8-bounce Cycles) and Diffuse Color's share of equal pixels.
TARGETS = {"Combined": 0.08, "Diffuse Indirect": 0.15, "Diffuse Direct": 0.02, "Glossy Direct": 0.10}
MATCH_TARGET = 0.98
MARGIN_RULE = "measured + 2 x noise floor + 0.001 (float16 storage), rounded up to 3 decimals"


def table_passes():
    from examples import references

    return references.PASSES + (DERIVED,)


# --------------------------------------------------------------------------- measuring (needs bpy)

def compare(ours: dict, ref) -> dict:
    """rel-L1 per pass (None where Cycles' pass is 0 on the compared pixels) and the Diffuse Color match, for our
    render's passes against a CommittedReference; a pass we do not write is 1.0 and listed in "missing"."""
    import numpy as np

    from bounce_gi.addon.reference.compare import geometry_mask
    from bounce_gi.gpu_kernels.output import metrics
    from examples import references

    mask = geometry_mask(ours, ref.passes)
    out, missing = {}, []

    def rel(x, r):
        v = metrics.rel_l1(x, r, mask)
        return None if not math.isfinite(v) else round(v, 6)

    zero = []  # passes we write as 0 on every compared pixel (LPV's Glossy Indirect): rel-L1 exactly 1
    for name in references.PASSES:
        r = ref.passes[name]
        if name in ours:
            out[name] = rel(ours[name], r)
            if out[name] is not None and not np.any(ours[name][..., :3][mask]):
                zero.append(name)
        else:
            missing.append(name)
            out[name] = 1.0 if float(np.abs(r[mask]).sum()) > 0 else None  # all of Cycles' light is missing
    dd = [ours.get(p) for p in ("Diffuse Direct", "Diffuse Indirect")]
    if all(p is not None for p in dd):
        out[DERIVED] = rel(dd[0][..., :3] + dd[1][..., :3],
                           ref.passes["Diffuse Direct"] + ref.passes["Diffuse Indirect"])
    else:
        out[DERIVED] = 1.0
    # Diffuse Indirect's mean over the compared pixels, ours / Cycles': too bright (> 1) or too dark, at a glance.
    di_ref = float(ref.passes["Diffuse Indirect"][mask].sum())
    di_ratio = float(ours["Diffuse Indirect"][..., :3][mask].sum()) / di_ref if di_ref > 0 else None
    diff = np.abs(ours["Diffuse Color"][..., :3] - ref.passes["Diffuse Color"]).max(axis=-1)
    match = float(np.mean(diff[mask] <= MATCH_TOLERANCE)) if mask.any() else float("nan")
    return {"rel_l1": out, MATCH: round(match, 6), "missing": missing, "zero": zero, "pixels": int(mask.sum()),
            "di_ratio": None if di_ratio is None else round(di_ratio, 4)}


def measure(names, methods, directory=None, lpv_pairs=(), vct_pairs=()) -> dict:
    """{scene: {"noise_floor", "diffuse_color_unstable", "samples", "stale", method: comparison}}; renders each
    scene with each method in this process (bpy)."""
    import bpy

    from bounce_gi.addon.cli import parse_method_options, render_ours, vct_options
    from bounce_gi.addon.extract import extract_scene
    from examples import references

    directory = directory or references.DIR
    out = {}
    for name in names:
        ref = references.load(name, directory)
        references.build(name)
        row = {"noise_floor": ref.meta["noise_floor"], "diffuse_color_unstable": ref.meta["diffuse_color_unstable"],
               "samples": ref.meta["samples"], "stale": references.stale(ref)}
        scene = extract_scene(bpy.context.evaluated_depsgraph_get())
        for method in methods:
            t0 = time.perf_counter()
            result = render_ours(scene, method, parse_method_options(list(lpv_pairs)), vct_options(list(vct_pairs)))
            row[method] = compare(result.passes, ref)
            row[method]["seconds"] = round(time.perf_counter() - t0, 2)
            row[method]["warnings"] = result.warnings
        out[name] = row
        print(f"{name}: " + "; ".join(f"{m} {row[m]['seconds']:.1f} s" for m in methods), file=sys.stderr, flush=True)
    return out


# --------------------------------------------------------------------------- bounds and the table (plain Python)

def _up(x: float) -> float:
    return math.ceil(x * 1000 - 1e-9) / 1000


def _down(x: float) -> float:
    return math.floor(x * 1000 + 1e-9) / 1000


def suggested_bound(name: str, measured: float, floor: float | None, absent: bool = False) -> float:
    """The regression bound of one rel-L1 (MARGIN_RULE), or the target where the measurement meets it; exactly
    1.0 for a pass we do not write or write as 0 (its rel-L1 is 1 whatever the reference's noise)."""
    if absent:
        return 1.0
    bound = _up(measured + 2.0 * (floor or 0.0) + 0.001)
    target = TARGETS.get(name)
    if target is not None and measured <= target:
        bound = min(bound, target)
    return bound


def suggested_match_bound(measured: float, unstable: float) -> float:
    bound = max(0.0, _down(measured - 2.0 * unstable - 0.001))
    return max(bound, MATCH_TARGET) if measured >= MATCH_TARGET else bound


def suggested_bounds(data: dict, methods=METHODS) -> dict:
    bounds = {}
    for name, row in data.items():
        bounds[name] = {}
        for m in methods:
            if m not in row:
                continue
            absent = set(row[m]["missing"]) | set(row[m]["zero"])
            b = {p: suggested_bound(p, v, row["noise_floor"].get(p), p in absent)
                 for p, v in row[m]["rel_l1"].items() if v is not None}
            b[MATCH] = suggested_match_bound(row[m][MATCH], row["diffuse_color_unstable"])
            bounds[name][m] = b
    return bounds


def format_bounds(bounds: dict) -> str:
    """The BOUNDS dict as Python source, one scene x method a line."""
    lines = ["BOUNDS = {"]
    for name, methods in bounds.items():
        lines.append(f"    {name!r}: {{")
        for m, b in methods.items():
            lines.append(f"        {m!r}: {{" + ", ".join(f"{p!r}: {v:.3f}" for p, v in b.items()) + "},")
        lines.append("    },")
    lines.append("}")
    return "\n".join(lines)


def _cell(v, target=None) -> str:
    if v is None:
        return "—"
    mark = "" if target is None or v <= target else " ✗"
    return f"{v:.3f}{mark}"


def format_table(data: dict, methods=METHODS) -> str:
    """Markdown: a row per scene x method (✗: the issue's target missed) and a row of the reference's noise floors."""
    passes = table_passes()
    head = ["scene", "method", *passes, MATCH, "DI / Cycles", "s"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, row in data.items():
        for m in methods:
            if m not in row:
                continue
            r = row[m]
            cells = [_cell(r["rel_l1"].get(p), TARGETS.get(p)) for p in passes]
            match = r[MATCH]
            cells.append(f"{match:.1%}" + (" ✗" if match < MATCH_TARGET else ""))
            cells.append("—" if r.get("di_ratio") is None else f"{r['di_ratio']:.2f}")
            lines.append(f"| {name} | {m} | " + " | ".join(cells) + f" | {r['seconds']:.1f} |")
        floors = [_cell(row["noise_floor"].get(p)) for p in passes]
        lines.append(f"| {name} | *noise floor* ({row['samples']} spp) | " + " | ".join(floors)
                     + f" | {row['diffuse_color_unstable']:.1%} unstable | | |")
    missing = sorted({p for row in data.values() for m in methods if m in row for p in row[m]["missing"]})
    notes = ["", "rel-L1 over the pixels that hit geometry in both renders; — : Cycles' pass is 0 there; "
             f"✗ : the issue's target missed (Combined ≤ 0.08, Diffuse Indirect ≤ 0.15, Diffuse Direct ≤ 0.02, "
             f"Glossy Direct ≤ 0.10, Diffuse Color within {MATCH_TOLERANCE} on ≥ 98% of pixels). {DERIVED} = Diffuse "
             "Direct + Indirect (Cycles counts world light as direct)."]
    if missing:
        notes.append(f"Passes our renderer does not write (counted as 1.0): {', '.join(missing)}.")
    zero = sorted({f"{p} ({m})" for row in data.values() for m in methods if m in row for p in row[m]["zero"]})
    if zero:
        notes.append(f"Passes written as 0 where Cycles' is not (rel-L1 1.0): {', '.join(zero)}.")
    stale = [f"{n}: {row['stale']}" for n, row in data.items() if row.get("stale")]
    notes += [f"STALE {s}" for s in stale]
    return "\n".join(lines + notes)


def main(argv=None) -> int:
    from examples import references

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME")
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    parser.add_argument("--references", help="directory of the references (default: examples/references)")
    parser.add_argument("--lpv", nargs="+", default=[], metavar="KEY=VALUE", help="LPV settings (default: defaults)")
    parser.add_argument("--vct", nargs="+", default=[], metavar="KEY=VALUE", help="VCT settings (default: defaults)")
    parser.add_argument("--json", action="store_true", help="print `RESULT {json}` only")
    args = parser.parse_args(argv)
    names = args.names or list(references.FRAMES)
    unknown = [n for n in names if n not in references.FRAMES]
    if unknown:
        parser.error(f"no committed reference for {' '.join(unknown)}; known: {' '.join(references.FRAMES)}")
    data = measure(names, args.methods, args.references, args.lpv, args.vct)
    sys.stdout.flush()
    if args.json:
        print("RESULT " + json.dumps(data), flush=True)
        return 0
    print(format_table(data, args.methods))
    print(f"\n# bounds: {MARGIN_RULE}; the target where met")
    print(format_bounds(suggested_bounds(data, args.methods)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
