# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi bench`: the report's shape on one small example (real Cycles, real renders), the pure parts (Pareto
front, speed-up interpolation, log-log slope, automatic quality's choice) on constructed inputs, and bad input.

No assertion here is about time: speed is what the benchmark prints, not what tests hold (brief, Standards).
"""
import json
import math
import os
import subprocess
import sys
import textwrap

import pytest

from test_cli import CLI, ROOT, assert_bad_input, describe

MAKE_BLEND = r"""
import sys
sys.path.insert(0, sys.argv[1])
from examples import scenes
scenes.save("cornell", sys.argv[2])
"""


def run(env, *args, timeout=600):
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout, cwd=ROOT, env=env)


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    import importlib.util

    if importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy not installed in this interpreter")
    base = tmp_path_factory.mktemp("bench_env")
    e = {k: v for k, v in os.environ.items() if k != "BOUNCE_GI_DEBUG"}
    e.update(BLENDER_USER_RESOURCES=str(base / "blender_user"), BOUNCE_GI_CACHE=str(base / "cache"))
    return e


@pytest.fixture(scope="module")
def cornell(tmp_path_factory, env):
    path = tmp_path_factory.mktemp("bench_blend") / "cornell.blend"
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(MAKE_BLEND), ROOT, str(path)], capture_output=True,
                          text=True, timeout=180, cwd=ROOT, env=env)
    assert proc.returncode == 0, describe(proc)
    return path


@pytest.fixture(scope="module")
def quick(env, cornell, tmp_path_factory):
    """One `bench --quick` at 48x36 (the smallest size at which the Cornell box still has a few hundred pixels)."""
    out = tmp_path_factory.mktemp("bench_out")
    proc = run(env, "bench", cornell, "--quick", "--res", 48, 36, "--out", out, "--json")
    assert proc.returncode == 0, describe(proc)
    return json.loads(proc.stdout.strip().splitlines()[-1]), out


def test_quick_report_shape(quick):
    report, out = quick
    assert set(report) >= {"scenes", "plots", "summary", "quality_table", "machine"}
    (scene,) = report["scenes"]
    assert scene["reference"]["samples"] == 64 and scene["reference"]["seeds"] == 2
    assert all(math.isfinite(v) and v >= 0 for v in scene["reference"]["noise_floor"].values())
    for row in scene["rows"]:
        assert set(row) >= {"method", "settings", "default", "seconds", "passes", "rel_l1", "rel_mse", "flip"}
        assert "error" not in row, row
        assert row["seconds"] > 0 and row["passes"]["extract"] >= 0
        for value in (row["rel_l1"]["combined"], row["rel_l1"]["diffuse_indirect"], row["rel_mse"], row["flip"]):
            assert value is not None and math.isfinite(value) and value >= 0, row
        assert 0 <= row["flip"] <= 1
    # exactly one default row per method, and it is what `render` uses (the dataclass defaults)
    for method in ("none", "lpv", "vct"):
        defaults = [r for r in scene["rows"] if r["method"] == method and r["default"]]
        assert len(defaults) == 1, method
    from bounce_gi.addon.bench.sweep import default_settings

    for r in scene["rows"]:
        assert r["default"] == (r["settings"] == default_settings(r["method"]) or r["method"] == "none")
    # the indirect methods actually add light: their Diffuse Indirect error is below direct-only's 1.0
    none = next(r for r in scene["rows"] if r["method"] == "none")
    assert none["rel_l1"]["diffuse_indirect"] == pytest.approx(1.0)
    for r in scene["rows"]:
        if r["method"] != "none":
            assert r["rel_l1"]["diffuse_indirect"] < 0.9, r


def test_quick_peers(quick):
    report, _ = quick
    peers = report["scenes"][0]["peers"]
    cycles = [p for p in peers if p["engine"] == "CYCLES"]
    assert {(p["samples"], p["denoise"]) for p in cycles} == {(s, d) for s in (1, 4, 16) for d in (False, True)}
    for p in cycles:
        assert "error" not in p, p
        assert p["seconds"] > 0 and math.isfinite(p["rel_l1"]["combined"])
    # Cycles' own error must fall with samples (1 → 16 spp: noise ∝ 1/√spp, 4× less); if it did not, the peer
    # renders would not be what the reference is (wrong settings/seed handling).
    plain = {p["samples"]: p["rel_l1"]["combined"] for p in cycles if not p["denoise"]}
    assert plain[16] < 0.6 * plain[1]
    eevee = [p for p in peers if p["engine"] != "CYCLES"]
    assert len(eevee) == 1 and "skipped in --quick" in eevee[0]["error"]


def test_quick_files(quick):
    report, out = quick
    (plot,) = report["plots"]
    assert os.path.dirname(plot) == str(out)
    with open(plot, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    import OpenImageIO as oiio

    pixels = oiio.ImageBuf(plot).get_pixels(oiio.FLOAT)
    assert pixels.shape[:2] == (520, 860) and pixels.std() > 0.01  # not a blank canvas
    summary = open(report["summary"]).read()
    assert "| vct |" in summary and "| CYCLES | 16 spp + OIDN |" in summary and "Speed-up" in summary
    from bounce_gi.addon.quality import load_table

    table = load_table(report["quality_table"])
    assert {e["method"] for e in table["entries"]} == {"none", "lpv", "vct"}
    assert any(e["pareto"] for e in table["entries"])
    assert not [f for f in os.listdir(out) if f.endswith(".tmp")]  # nothing half-written


def test_incremental_reruns_only_what_changed(env, cornell):
    proc = run(env, "bench", cornell, "--incremental", "--quick", "--res", 40, 30, "--json")
    assert proc.returncode == 0, describe(proc)
    (entry,) = json.loads(proc.stdout.strip().splitlines()[-1])["incremental"]
    assert entry["peers"]["cycles_1spp_oidn"] > 0  # timed in the same run
    assert [m["resolution"] for m in entry["lpv_transfer_memory"]] == [32, 64, 128]
    for method, m in entry["methods"].items():
        for kind in ("full", "unchanged", "camera_only", "light_move", "light_power", "material_change",
                     "world_change", "object_move"):
            assert m[kind] is not None and m[kind] > 0, (method, kind)
        rerun = {k: set(d["rerun"]) for k, d in m["detail"].items()}
        assert rerun["unchanged"] == set(), method
        # a camera move changes what the camera sees, never the light transport of the scene
        assert rerun["camera_only"] >= {"gbuffer", "compose"}, method
        assert not rerun["camera_only"] & {"geometry", "shadow_maps", "rsm", "lpv_propagate", "vct_voxelize",
                                           "vct_inject"}, method
        assert "geometry" not in rerun["light_move"] and "shadow_maps" in rerun["light_move"], method
        assert "geometry" in rerun["object_move"], method
    # the LPV's cached transport: no edit of lights, materials or world rebuilds it
    lpv = {k: set(d["rerun"]) for k, d in entry["methods"]["lpv"]["detail"].items()}
    for kind in ("light_move", "light_power", "material_change", "world_change"):
        assert not lpv[kind] & {"geometry_volume", "lpv_transfer"}, kind
    assert "lpv_transfer" in lpv["object_move"] and "lpv_albedo" in lpv["material_change"]
    # a world colour edit is a light edit (the world is the sky light, common/lights.py): it re-runs the lights'
    # passes and the bounce series (the transfer is kept: checked above)
    assert {"shadow_maps", "rsm", "lpv_inject", "lpv_propagate"} <= lpv["world_change"]


def test_bad_input(env, cornell, tmp_path):
    assert_bad_input(run(env, "bench", tmp_path / "missing.blend", "--quick"), "no such file")
    assert_bad_input(run(env, "bench", "--quick"), "at least one .blend")
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    assert_bad_input(run(env, "bench", cornell, "--quick", "--out", a_file), "not a directory")
    assert_bad_input(run(env, "render", cornell, "--budget-ms", "-5"), "positive")
    assert_bad_input(run(env, "render", cornell, "--budget-ms", "100", "--lpv", "bounces=2"), "leave out --lpv")


def test_budget_picks_from_the_committed_table(env, cornell, tmp_path):
    from bounce_gi.addon.quality import load_table

    table = load_table()
    entries = table["entries"]
    most_accurate = min(entries, key=lambda e: e["rel_l1"])
    proc = run(env, "render", cornell, "--res", 40, 30, "--budget-ms", 1e9, "--out", tmp_path / "a.exr", "--json")
    assert proc.returncode == 0, describe(proc)
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert report["method"] == most_accurate["method"] == report["quality"]["method"]
    assert report["quality"]["settings"] == most_accurate["settings"]
    assert "chose" in report["quality"]["message"]
    fastest_vct = min((e for e in entries if e["method"] == "vct"), key=lambda e: e["seconds"])
    proc = run(env, "render", cornell, "--res", 40, 30, "--method", "vct", "--budget-ms", 1e-3,
               "--out", tmp_path / "b.exr")
    assert proc.returncode == 0, describe(proc)
    assert proc.stdout.startswith("chose ") and "nothing measured fits" in proc.stdout.splitlines()[0]
    assert fastest_vct["label"] in proc.stdout.splitlines()[0]


# --------------------------------------------------------------------------- pure parts, constructed inputs

def _row(method, seconds, err, settings=None):
    return {"method": method, "settings": settings or {}, "default": False, "seconds": seconds,
            "rel_l1": {"combined": err}}


def _peer(samples, seconds, err, denoise=False):
    return {"engine": "CYCLES", "samples": samples, "denoise": denoise, "seconds": seconds,
            "rel_l1": {"combined": err}}


def test_pareto_front():
    from bounce_gi.addon.bench.front import pareto

    rows = [_row("none", 0.01, 0.5), _row("lpv", 1.0, 0.3, {"resolution": 16, "bounces": 1}),
            _row("vct", 0.5, 0.2, {"resolution": 64, "bounces": 1})]
    peers = [_peer(1, 0.02, 0.6), _peer(16, 2.0, 0.1)]
    labels = [p["label"] for p in pareto(rows, peers)]
    # lpv is dominated by vct (slower and worse); Cycles 1 spp by none; the rest form the front, by time
    assert labels == ["none", "vct resolution=64 bounces=1", "CYCLES 16 spp"]


def test_peer_time_at_error_interpolates_log_log():
    from bounce_gi.addon.bench.front import peer_time_at_error

    # an exact power law err = 0.4·t^(-1/2): log-log interpolation must recover it between points
    peers = [_peer(s, t, 0.4 * t ** -0.5) for s, t in ((1, 0.01), (4, 0.04), (16, 0.16))]
    t, how = peer_time_at_error(peers, 0.4 * 0.02 ** -0.5, False)
    assert how == "interpolated" and t == pytest.approx(0.02, rel=1e-9)
    assert peer_time_at_error(peers, 100.0, False) == (0.01, "at most")
    assert peer_time_at_error(peers, 0.01, False) == (None, "beyond")
    assert peer_time_at_error(peers, 0.1, True) == (None, "no curve")


def test_log_log_slope():
    from bounce_gi.addon.bench.scaling import fit_slope

    xs = [10, 100, 1000, 10000]
    assert fit_slope(xs, [3 * x ** 0.75 for x in xs]) == pytest.approx(0.75)
    assert fit_slope([5], [1.0]) is None


def test_synthetic_scaling_scene_has_the_stated_triangle_count():
    from bounce_gi.addon.bench.scaling import synthetic_scene

    assert synthetic_scene(3).triangle_count == 2 + 20 * 4 ** 3


def test_quality_choice():
    from bounce_gi.addon.quality import QualityError, choose

    table = {"entries": [
        {"method": "none", "settings": {}, "seconds": 0.01, "rel_l1": 0.45, "label": "none"},
        {"method": "vct", "settings": {"resolution": 32}, "seconds": 0.2, "rel_l1": 0.2, "label": "vct 32"},
        {"method": "vct", "settings": {"resolution": 64}, "seconds": 0.6, "rel_l1": 0.15, "label": "vct 64"},
        {"method": "lpv", "settings": {"resolution": 16}, "seconds": 0.4, "rel_l1": 0.25, "label": "lpv 16"}]}
    assert choose(table, budget_ms=500).label == "vct 32"  # most accurate within 0.5 s
    assert choose(table, budget_ms=5000).label == "vct 64"
    assert choose(table, target_error=0.3).label == "vct 32"  # fastest reaching 0.3
    assert choose(table, target_error=0.18, budget_ms=300).label == "vct 32"  # target unreachable in time
    assert "none reaches" in choose(table, target_error=0.18, budget_ms=300).reason
    assert choose(table, budget_ms=1).label == "none" and "nothing measured fits" in choose(table, budget_ms=1).reason
    assert choose(table, budget_ms=1000, method="lpv").label == "lpv 16"
    assert choose(table, target_error=0.01).label == "vct 64"  # nothing reaches it: the most accurate
    with pytest.raises(QualityError):
        choose(table)
    with pytest.raises(QualityError):
        choose(table, budget_ms=float("nan"))
