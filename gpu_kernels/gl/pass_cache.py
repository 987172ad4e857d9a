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
    """Runs passes, caches their outputs by key and records seconds per pass for the current frame.

    A pass keeps one output (`entries[name]`, the newest), or up to `keep[name]` of them: the live viewport
    alternates a draft and a final setting, whose geometry-bound outputs (the LPV's transfer) would otherwise
    evict each other on every edit."""
    finish: object = None  # callable that waits for the GPU (ctx.finish) so timings are honest
    entries: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    skipped: list = field(default_factory=list)
    keep: dict = field(default_factory=dict)  # pass name → outputs kept (default 1)
    older: dict = field(default_factory=dict)  # pass name → outputs kept besides the newest, newest first

    def begin_frame(self) -> None:
        self.timings = {}
        self.skipped = []

    def run(self, name: str, key: tuple, fn):
        """Return the cached output of `name` if `key` matches one kept, else run `fn()` (timed) and cache it."""
        entry = self.entries.get(name)
        if entry is None or entry.key != key:
            found = next((e for e in self.older.get(name, []) if e.key == key), None)
            if found is not None:
                self.older[name].remove(found)
                self._retire(name, entry)
                self.entries[name] = entry = found
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
            self._retire(name, entry)
        self.entries[name] = _Entry(key, value)
        return value

    def kept(self, name: str) -> list:
        """The outputs kept for `name` as (key, value), newest first (a pass may update one instead of starting
        over: the LPV's transfer after a geometry edit)."""
        entries = ([self.entries[name]] if name in self.entries else []) + self.older.get(name, [])
        return [(e.key, e.value) for e in entries]

    def prior(self, name: str, match) -> object:
        """The newest kept output of `name` whose key `match(key)` accepts, or None: what a pass may update instead
        of starting over (the depth atlas, the RSM, the first bounce, Diffuse Direct after a light edit)."""
        return next((value for key, value in self.kept(name) if match(key)), None)

    def spare(self, name: str, besides=None) -> object:
        """The output that storing a new one of `name` would release (the oldest kept, once `keep[name]` are kept),
        taken out of the cache and handed to the caller, who may write the new output into its memory and releases
        the rest of it; None where none would go, or where that one `is besides` (the prior the new output is made
        from). Writing into memory already in use spares the kernel's page faults: a new 100 MB array cost more to
        touch the first time than the copy into it (the LPV's transfer after a geometry edit)."""
        older = self.older.get(name, [])
        if name not in self.entries or not older or len(older) < self.keep.get(name, 1) - 1:
            return None
        if older[-1].value is besides:
            return None
        return older.pop().value

    def drop(self, names) -> None:
        """Release every output kept for the passes `names` (a pass the frame no longer runs, which would otherwise
        hold its memory until the cache is cleared)."""
        for name in names:
            entry = self.entries.pop(name, None)
            for e in ([entry] if entry is not None else []) + self.older.pop(name, []):
                release_resources(e.value)

    def _retire(self, name: str, entry) -> None:
        """Keep a replaced output among the `keep[name] - 1` older ones, releasing what falls off the end."""
        if entry is None:
            return
        older = self.older.setdefault(name, [])
        older.insert(0, entry)
        while len(older) > self.keep.get(name, 1) - 1:
            release_resources(older.pop().value)

    def clear(self) -> None:
        for entry in list(self.entries.values()) + [e for es in self.older.values() for e in es]:
            release_resources(entry.value)
        self.entries.clear()
        self.older.clear()
