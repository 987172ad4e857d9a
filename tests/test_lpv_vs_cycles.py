"""LPV against full-bounce Cycles on the typical interiors (issue: Light Propagation Volumes) — regression bounds.

These hold today's measured errors (160×120, 32³ grid, 3 bounces, Cycles 128 spp × 2 seeds, 8 bounces) plus a
margin of about 0.05 for the reference noise (its floor on Diffuse Indirect is ~0.1 here at 128 spp, and half of it
can move our rel-L1 either way). They are NOT the issue's targets (Diffuse Indirect ≤ 25%, Combined ≤ 10%): the
2-band propagation is diffusive (light random-walks between cells), which puts too much bounced light near where it
was injected (see the closing note of the LPV work). A change that makes LPV worse fails here; one that makes it
better should lower these bounds.
"""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"cornell": {"diffuse_indirect": 0.80, "combined": 0.40}}


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    env = dict(os.environ, BOUNCE_GI_CACHE=os.environ.get("BOUNCE_GI_TEST_CACHE",
                                                           str(tmp_path_factory.mktemp("refcache"))),
               BLENDER_USER_RESOURCES=str(tmp_path_factory.mktemp("blender_user")))
    proc = subprocess.run([sys.executable, str(ROOT / "tests/support/compare_examples.py"), "128", *SCENES,
                           "--method", "lpv", "--lpv", "bounces=3"], capture_output=True, text=True, env=env,
                          timeout=900)
    line = next((l for l in proc.stdout.splitlines() if l.startswith("RESULT ")), None)
    assert proc.returncode == 0 and line, f"comparison run failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    data = json.loads(line[len("RESULT "):])
    for name, r in data.items():
        print(name, "LPV rel-L1", {k: round(v, 3) for k, v in r["rel_l1"].items()}, "noise floor",
              {k: round(v, 3) for k, v in r["noise_floor"].items()})
    return data


@pytest.mark.parametrize("name", list(SCENES))
def test_lpv_error_does_not_regress(results, name):
    r = results[name]
    for key, bound in SCENES[name].items():
        assert r["rel_l1"][key] <= bound, (key, r["rel_l1"], r["noise_floor"])
    # The direct light is the same as method 'none' (its own accuracy is tested in test_direct_vs_cycles).
    assert r["rel_l1"]["diffuse_direct"] <= 0.03
