# SPDX-License-Identifier: GPL-3.0-or-later
"""A tiny pass graph: each pass names its inputs, is timed, and is skipped while its inputs are unchanged.

A pass's key is built from the content hashes of the scene parts it reads (geometry, materials, lights, camera,
world, settings) and the keys of the passes it consumes, so a change re-runs exactly the passes downstream of it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field


def release_resources(value) -> None:
    """Release GL objects held in a pass output (objects with .release(), nested in dicts/lists/tuples)."""
    if value is None:
        return
    if isinstance(value, dict):
        for v in value.values():
            release_resources(v)
    elif isinstance(value, (list, tuple)):
        for v in value:
            release_resources(v)
    elif hasattr(value, "release") and callable(value.release):
        value.release()


@dataclass
class _Entry:
    key: tuple
    value: object


@dataclass
class PassCache:
    """Runs passes, caches their outputs by key and records seconds per pass for the current frame."""
    finish: object = None  # callable that waits for the GPU (ctx.finish) so timings are honest
    entries: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    skipped: list = field(default_factory=list)

    def begin_frame(self) -> None:
        self.timings = {}
        self.skipped = []

    def run(self, name: str, key: tuple, fn):
        """Return the cached output of `name` if `key` matches, else run `fn()` (timed) and cache it."""
        entry = self.entries.get(name)
        if entry is not None and entry.key == key:
            self.timings[name] = 0.0
            self.skipped.append(name)
            return entry.value
        start = time.perf_counter()
        value = fn()
        if self.finish is not None:
            self.finish()
        self.timings[name] = time.perf_counter() - start
        if entry is not None and entry.value is not value:
            release_resources(entry.value)
        self.entries[name] = _Entry(key, value)
        return value

    def clear(self) -> None:
        for entry in self.entries.values():
            release_resources(entry.value)
        self.entries.clear()
