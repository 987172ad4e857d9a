# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi compare`'s table: a pass Cycles renders black over every compared pixel has no relative error (0/0),
and says so instead of printing nan."""
from bounce_gi.addon.cli.compare import format_compare


def _report(rel_l1):
    return {"method": "lpv", "resolution": [160, 120], "reference": {"samples": 256, "bounces": 8},
            "rel_l1": rel_l1, "noise_floor": {k: 0.01 for k in rel_l1}, "rel_mse": 0.0, "diffuse_color_match": 1.0,
            "seconds": {"ours": 1.0, "cycles": 2.0, "cycles_cached": True}, "warnings": []}


def test_a_pass_black_in_cycles_prints_a_dash_and_why_not_nan():
    text = format_compare(_report({"combined": 0.0213, "diffuse_indirect": float("nan")}))
    assert "nan" not in text
    lines = {line.split()[0]: line for line in text.splitlines() if line.startswith(("combined", "diffuse"))}
    assert "0.0213" in lines["combined"] and "0.0100" in lines["combined"]
    assert "—" in lines["diffuse_indirect"] and "Cycles' pass is 0" in lines["diffuse_indirect"]
