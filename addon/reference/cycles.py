# SPDX-License-Identifier: GPL-3.0-or-later
"""Cycles ground truth: two-seed reference renders with the settings of docs/conventions.md (Cycles references), cached by content hash.

Settings: CPU, adaptive sampling off, denoising off, clamps 0, light threshold 0, pixel filter 0.01 px (so Cycles
samples pixel centres like our rasteriser), fixed bounce counts. The mean of the two seeds is the reference; half
the rel-L1 between the seeds is the reference's own noise floor, reported beside every error.
The user's scene is restored after rendering (every render, Cycles, image and view layer setting is put back as it
was: settings_snapshot.py), so nothing is changed in the .blend. ReferenceJob renders seed by seed for callers that
run Blender's render job themselves (the compare operator).
"""
from __future__ import annotations

import json
import os
import tempfile
import time
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ...gpu_kernels.output import exr as exr_io
from ...gpu_kernels.output import metrics

PASS_FLAGS = ("use_pass_diffuse_direct", "use_pass_diffuse_indirect", "use_pass_diffuse_color", "use_pass_emit",
              "use_pass_normal", "use_pass_z", "use_pass_position", "use_pass_glossy_direct",
              "use_pass_glossy_indirect", "use_pass_glossy_color")
COMPARED_PASSES = ("Combined", "Diffuse Direct", "Diffuse Indirect", "Diffuse Color")


@dataclass(frozen=True)
class ReferenceSettings:
    width: int
    height: int
    samples: int = 256
    seeds: tuple = (1, 2)
    bounces: int = 8  # diffuse (and total) bounces; 1 = one indirect bounce; fixed so results are comparable


@dataclass
class Reference:
    passes: dict  # mean of the seeds
    seeds: list  # per-seed passes
    seconds: float  # Cycles render time (sum over seeds) when rendered now; the cached value otherwise
    cached: bool

    def noise_floor(self, name: str, mask=None) -> float:
        """Half the rel-L1 between the two seeds: the error the reference itself carries."""
        a, b = self.seeds[0][name], self.seeds[1][name]
        return 0.5 * metrics.rel_l1(a, b, mask)


def cache_dir() -> Path:
    root = os.environ.get("BOUNCE_GI_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "bounce-gi")
    return Path(root) / "references"


def cache_key(scene_hash: str, settings: ReferenceSettings) -> str:
    import hashlib

    import bpy

    text = json.dumps([scene_hash, asdict(settings), bpy.app.version_string], sort_keys=True, default=str)
    return hashlib.sha1(text.encode()).hexdigest()[:20]


@contextmanager
def saved_attributes(objects_attrs):
    """Remember (object, attribute) values and put them back afterwards."""
    saved = []
    for obj, attr in objects_attrs:
        try:
            saved.append((obj, attr, getattr(obj, attr)))
        except AttributeError:
            pass
    try:
        yield
    finally:
        for obj, attr, value in reversed(saved):
            try:
                setattr(obj, attr, value)
            except (AttributeError, TypeError):
                pass


def configure_cycles(scene, view_layer, settings: ReferenceSettings, seed: int, path: str) -> None:
    c, r = scene.cycles, scene.render
    r.engine = "CYCLES"
    c.device = "CPU"
    c.samples = settings.samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0  # defaults to 10: turn it off (docs/conventions.md)
    c.light_sampling_threshold = 0.0
    c.filter_width = 0.01
    c.seed = seed
    c.use_animated_seed = False
    b = settings.bounces
    c.max_bounces = b
    c.diffuse_bounces = b
    c.glossy_bounces = b
    c.transmission_bounces = b
    c.volume_bounces = 0
    c.transparent_max_bounces = 8
    c.caustics_reflective = True
    c.caustics_refractive = True
    r.resolution_x, r.resolution_y, r.resolution_percentage = settings.width, settings.height, 100
    r.use_border = False
    r.film_transparent = False
    for flag in PASS_FLAGS:
        if hasattr(view_layer, flag):
            setattr(view_layer, flag, True)
    im = r.image_settings
    if hasattr(im, "media_type"):
        im.media_type = "MULTI_LAYER_IMAGE"
    im.file_format = "OPEN_EXR_MULTILAYER"
    im.color_depth = "32"
    r.filepath = path


def settings_to_save(scene, view_layer):
    c, r = scene.cycles, scene.render
    attrs = [(r, a) for a in ("engine", "resolution_x", "resolution_y", "resolution_percentage", "use_border",
                              "film_transparent", "filepath")]
    attrs += [(c, a) for a in ("device", "samples", "use_adaptive_sampling", "use_denoising", "sample_clamp_direct",
                               "sample_clamp_indirect", "light_sampling_threshold", "filter_width", "seed",
                               "use_animated_seed", "max_bounces", "diffuse_bounces", "glossy_bounces",
                               "transmission_bounces", "volume_bounces", "transparent_max_bounces",
                               "caustics_reflective", "caustics_refractive")]
    attrs += [(view_layer, f) for f in PASS_FLAGS]
    im = r.image_settings
    attrs += [(im, "color_depth"), (im, "file_format")] + ([(im, "media_type")] if hasattr(im, "media_type") else [])
    return attrs


def render_reference(scene_hash: str, settings: ReferenceSettings, progress=None) -> Reference:
    """Render (or load from cache) the two-seed Cycles reference of the current bpy scene, blocking."""
    import bpy

    job = ReferenceJob(scene_hash, settings, bpy.context.scene, bpy.context.view_layer)
    return job.cached if job.cached is not None else run_blocking(job, progress)


def run_blocking(job: "ReferenceJob", progress=None) -> Reference:
    """Render every seed of `job` with `bpy.ops.render.render` (blocking) and return the Reference; the scene's
    render settings are restored whatever happens."""
    import bpy

    try:
        while not job.done:
            message = job.begin_seed()
            if progress:
                progress(message)
            bpy.ops.render.render(write_still=True)
            job.end_seed()
        return job.finish()
    finally:
        job.restore()


class ReferenceJob:
    """A two-seed reference rendered one seed at a time, so the caller runs each seed's render: render_reference
    blocks on `bpy.ops.render.render`, the compare operator starts Blender's render job and polls it.

    `cached` is the Reference when the cache has it (nothing to render). Otherwise, per seed: `begin_seed()` (the
    first call snapshots the scene's render settings, settings_snapshot.py, then Cycles is configured for the seed)
    → render to `seed_path` → `end_seed()`; then `finish()`. `restore()` puts every render setting back exactly and
    removes the temporary files; call it in a `finally` (it is idempotent), also after a cancelled render."""

    def __init__(self, scene_hash: str, settings: ReferenceSettings, scene, view_layer):
        self.settings, self.scene_hash, self.scene, self.view_layer = settings, scene_hash, scene, view_layer
        self.directory = cache_dir()
        key = cache_key(scene_hash, settings)
        self.meta_path = self.directory / f"{key}.json"
        self.cache_paths = [self.directory / f"{key}_seed{s}.exr" for s in settings.seeds]
        self.cached = self._load_cached()
        self.seeds, self.seconds = [], 0.0
        self.seed_path = None  # where the current seed's render is written
        self._snapshot, self._tmp, self._started, self._begun = None, None, 0.0, 0

    def _load_cached(self) -> Reference | None:
        if not (self.meta_path.exists() and all(p.exists() for p in self.cache_paths)):
            return None
        try:
            seeds = [exr_io.read_passes(str(p)) for p in self.cache_paths]
            seconds = json.loads(self.meta_path.read_text())["seconds"]
        except (OSError, ValueError, KeyError):
            return None  # a broken cache entry is simply rendered again
        return Reference(_mean(seeds), seeds, seconds, cached=True)

    @property
    def started_seeds(self) -> int:
        """Seeds begun so far (begin_seed calls); len(seeds) of them are rendered and read."""
        return self._begun

    @property
    def done(self) -> bool:
        return len(self.seeds) == len(self.settings.seeds)

    def begin_seed(self) -> str:
        """Configure Cycles for the next seed; returns a one-line description for progress."""
        from .settings_snapshot import snapshot

        if self._snapshot is None:
            self._snapshot = snapshot(self.scene, self.view_layer)
            self._tmp = tempfile.TemporaryDirectory(prefix="bounce-gi-ref-")
        i = len(self.seeds)
        seed = self.settings.seeds[i]
        self.seed_path = os.path.join(self._tmp.name, f"seed{seed}.exr")
        configure_cycles(self.scene, self.view_layer, self.settings, seed, self.seed_path)
        self._started = time.perf_counter()
        self._begun = i + 1
        st = self.settings
        return (f"Cycles reference: seed {seed} ({i + 1}/{len(st.seeds)}), {st.samples} samples at "
                f"{st.width}x{st.height}")

    def end_seed(self) -> None:
        """Read the seed's render (written by the caller's render) and store it in the cache."""
        self.seconds += time.perf_counter() - self._started
        passes = exr_io.read_passes(self.seed_path)
        self.directory.mkdir(parents=True, exist_ok=True)
        exr_io.write_passes(str(self.cache_paths[len(self.seeds)]), passes)
        self.seeds.append(passes)

    def finish(self) -> Reference:
        self.meta_path.write_text(json.dumps({"seconds": self.seconds, "settings": asdict(self.settings),
                                              "scene": self.scene_hash}))
        self.restore()
        return Reference(_mean(self.seeds), self.seeds, self.seconds, cached=False)

    def restore(self) -> None:
        from .settings_snapshot import restore

        snap, self._snapshot = self._snapshot, None
        if snap is not None:
            restore(snap)
        tmp, self._tmp = self._tmp, None
        if tmp is not None:
            tmp.cleanup()


def _mean(seeds: list) -> dict:
    names = set.intersection(*(set(s) for s in seeds))
    return {n: np.mean([s[n] for s in seeds], axis=0).astype(np.float32) for n in names}
