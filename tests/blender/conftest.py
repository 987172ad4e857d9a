# SPDX-License-Identifier: GPL-3.0-or-later
"""The example scenes' summary, collected once a session by test_examples.py run as a script in a subprocess (bpy's
state stays out of pytest), for test_examples.py and test_user_scenes.py."""
from pathlib import Path

import pytest

from support.bpy_summary import run_summary

HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="session")
def examples_summary():
    return run_summary(HERE / "test_examples.py", lambda out, tmp: ["--collect", out, tmp], HERE.parents[1])
