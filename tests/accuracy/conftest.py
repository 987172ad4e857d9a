# SPDX-License-Identifier: GPL-3.0-or-later
"""The accuracy suite's --slow switch: cases marked `slow` run only with it (CI's default run stays short)."""


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a long accuracy case, run with --slow")


def pytest_collection_modifyitems(config, items):
    """Without --slow the slow cases are deselected (not skipped: they are not missing work)."""
    if config.getoption("--slow"):
        return
    slow = [item for item in items if item.get_closest_marker("slow")]
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if not item.get_closest_marker("slow")]
