# SPDX-License-Identifier: GPL-3.0-or-later
"""Shared fixtures: one Cycles reference cache per test session, and the example-scene comparison runner."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# The folder a test lives in is its marker: unit (pure Python), gpu (moderngl on llvmpipe), blender (bpy in a
# subprocess), accuracy (against Cycles renders), stress (numerical stability and bad input, docs/stress.md).
# `make test-fast` runs `-m "unit or gpu"`.
MARKERS = ("unit", "gpu", "blender", "accuracy", "stress")


def pytest_addoption(parser):
    parser.addoption("--stress-full", action="store_true", default=False,
                     help="tests/stress: the longer cases too (larger grids, more bounces, more random scenes)")


def pytest_collection_modifyitems(items):
    for item in items:
        folder = Path(str(item.fspath)).parent.name
        if folder in MARKERS:
            item.add_marker(getattr(pytest.mark, folder))


@pytest.fixture(scope="session")
def reference_cache(tmp_path_factory):
    """Where Cycles references go: $BOUNCE_GI_TEST_CACHE to reuse them across runs, else fresh per session."""
    return os.environ.get("BOUNCE_GI_TEST_CACHE") or str(tmp_path_factory.mktemp("refcache"))


@pytest.fixture(scope="session")
def support_script(reference_cache, tmp_path_factory):
    """run(script, *args) → the JSON a tests/support script printed on its "RESULT " line, run in a subprocess (bpy's
    global state stays out of pytest) that shares the session's reference cache."""
    user = str(tmp_path_factory.mktemp("blender_user"))

    def run(script, *args, timeout=900):
        env = dict(os.environ, BOUNCE_GI_CACHE=reference_cache, BLENDER_USER_RESOURCES=user)
        proc = subprocess.run([sys.executable, str(ROOT / "tests/support" / script), *map(str, args)],
                              capture_output=True, text=True, env=env, timeout=timeout)
        line = next((l for l in proc.stdout.splitlines() if l.startswith("RESULT ")), None)
        assert proc.returncode == 0 and line, f"{script} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
        return json.loads(line[len("RESULT "):])

    return run


@pytest.fixture(scope="session")
def compare_examples(support_script):
    """run(samples, names, *args) → {name: compare report}: tests/support/compare_examples.py."""
    def run(samples, names, *args, timeout=900):
        data = support_script("compare_examples.py", samples, *names, *args, timeout=timeout)
        for name, r in data.items():
            print(name, *args, "rel-L1", {k: round(v, 3) for k, v in r["rel_l1"].items()}, "noise floor",
                  {k: round(v, 3) for k, v in r["noise_floor"].items()})
        return data

    return run


@pytest.fixture(scope="session")
def check_bounds():
    """check(report, bounds): every rel-L1 in `bounds` is within its bound, and Diffuse Direct — the same direct
    light for every method, its own accuracy tested in test_direct_vs_cycles — within 3%."""
    def check(report, bounds):
        for key, bound in bounds.items():
            assert report["rel_l1"][key] <= bound, (key, report["rel_l1"], report["noise_floor"])
        assert report["rel_l1"]["diffuse_direct"] <= 0.03

    return check
