# SPDX-License-Identifier: GPL-3.0-or-later
"""The example scenes' summary, collected once a session by test_examples.py run as a script in a subprocess (bpy's
state stays out of pytest), for test_examples.py and test_user_scenes.py."""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="session")
def examples_summary():
    if importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy not installed in this interpreter")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "summary.json")
        env = {**os.environ, "BLENDER_USER_RESOURCES": os.path.join(tmp, "blender_user")}
        proc = subprocess.run([sys.executable, str(HERE / "test_examples.py"), "--collect", out, tmp],
                              capture_output=True, text=True, timeout=300, cwd=HERE.parents[1], env=env)
        assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
        with open(out) as f:
            return json.load(f)
