# SPDX-License-Identifier: GPL-3.0-or-later
"""A bpy script run in a subprocess (bpy's global state stays out of pytest) that writes a JSON summary: the tests'
one way to collect what Blender computed."""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile

import pytest


def run_summary(script, args, cwd, extra_env=None, timeout=300) -> dict:
    """Run `script` with `args(out, tmp)` (out: the JSON file it must write, tmp: a scratch folder) and return its
    JSON; `extra_env` values may name the scratch folder as {tmp}. Skips where bpy is not installed, fails with the
    script's output where it exits non-zero."""
    if importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy not installed in this interpreter")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "summary.json")
        env = {**os.environ, "BLENDER_USER_RESOURCES": os.path.join(tmp, "blender_user"),
               **{k: v.format(tmp=tmp) for k, v in (extra_env or {}).items()}}
        proc = subprocess.run([sys.executable, str(script), *args(out, tmp)],
                              capture_output=True, text=True, timeout=timeout, cwd=cwd, env=env)
        assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
        with open(out) as f:
            return json.load(f)
