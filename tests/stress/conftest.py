# SPDX-License-Identifier: GPL-3.0-or-later
"""The stress suite's shared engine (one GL context and pass cache for every case) and the --stress-full switch."""
import pytest

from bounce_gi.gpu_kernels.engine import Engine


@pytest.fixture(scope="session")
def engine():
    engine = Engine()
    yield engine
    engine.shutdown()


@pytest.fixture(scope="session")
def full(request) -> bool:
    """Whether --stress-full asked for the longer cases."""
    return bool(request.config.getoption("--stress-full"))


def pytest_configure(config):
    config.addinivalue_line("markers", "stress_full: a longer stress case, run with --stress-full")


def pytest_collection_modifyitems(config, items):
    """Without --stress-full the longer cases are deselected (not skipped: they are not missing work)."""
    if config.getoption("--stress-full"):
        return
    longer = [item for item in items if "stress_full" in item.keywords]
    if longer:
        config.hook.pytest_deselected(items=longer)
        items[:] = [item for item in items if "stress_full" not in item.keywords]
