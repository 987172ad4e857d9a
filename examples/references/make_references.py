# SPDX-License-Identifier: GPL-3.0-or-later
"""Render the committed Cycles references of the example scenes like users' (examples/references/).

    python examples/references/make_references.py [NAME ...] [--samples N] [--force] [--out DIR]

For each reference of examples.references.names() (or the named ones): build its scene (examples.scenes.build, at its
reference frame), render the project's two-seed Cycles reference with addon/reference/cycles.py (CPU, adaptive
sampling off, denoising off, clamps 0, light threshold 0, pixel filter 0.01 px, 8 bounces of every kind, seeds 1
and 2) at 160x120, and write <name>.npz (the two-seed mean of PASSES and Depth, float16) and <name>.json (settings,
the scene's fingerprint, Cycles' seconds, each pass's noise floor). A scene whose files already match its
fingerprint and settings is skipped unless --force. The Cycles renders are also cached like every reference
(~/.cache/bounce-gi or $BOUNCE_GI_CACHE).

Samples: 1024 per pixel and seed (examples.references.SAMPLES), not the 2048 the issue's table used. Timed here
(2 CPU cores shared with other work, 2026-12-02): `furnished` at 2048 spp x 2 seeds took 1005 s (17 min); the
other eleven at 1024 x 2 took 3757 s (63 min; lamp_room 888 s and many_lights 844 s the slowest, textured 99 s
the fastest). At 2048 the whole set would have taken about 2.4 hours, so it is rendered at 1024 x 2 (furnished,
the timing run, kept at 2048); each JSON records its samples and each pass's noise floor, which says what the
lower count costs (at 1024 spp Combined's floor is 0.002-0.046, Diffuse Indirect's 0.017-0.067). Re-run with
--samples 2048 --force on a faster machine to lower the floors by about 1/sqrt(2). The two rooms lit by the sky
through a window are at 16384 (references.SAMPLES_OF: their 1024-spp Diffuse Direct floor was above the issue's
target; 25 min each here, 2026-12-05).

The transport tests' references (examples.references.TRANSPORT: cornell, spot_room, courtyard at 8 bounces and at 1)
are rendered with 4096 samples (references.TRANSPORT_SAMPLES; 1.7-3 min each here, 2026-12-05): their tests hold
bounds of measured + 2 x the noise floor, so a lower floor is a tighter test.

Needs bpy; run with the repository root (or its parent, for `bounce_gi`) importable, like the tests.
"""
from __future__ import annotations

import argparse
import datetime
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

import bpy  # noqa: E402,F401  (before examples.scenes: it puts bmesh/mathutils on the path)
import numpy as np  # noqa: E402

from bounce_gi.addon.reference.cycles import ReferenceSettings, render_reference  # noqa: E402
from bounce_gi.gpu_kernels.output import metrics  # noqa: E402
from examples import references, scenes  # noqa: E402

RESOLUTION = scenes.RESOLUTION


def floors(seeds: list, hit: np.ndarray) -> dict:
    """Half the rel-L1 between the two seeds over `hit`, per pass (as cycles.Reference.noise_floor), and for the
    diffuse light (Direct + Indirect: Cycles counts world light as direct, we may not); None where the pass is 0."""
    out = {}
    a, b = seeds

    def floor(x, y):
        v = 0.5 * metrics.rel_l1(x, y, hit)
        return None if not np.isfinite(v) else round(v, 6)

    for name in references.PASSES:
        if name in a and name in b:
            out[name] = floor(a[name], b[name])
    out["Diffuse Light"] = floor(a["Diffuse Direct"] + a["Diffuse Indirect"], b["Diffuse Direct"] + b["Diffuse Indirect"])
    return out


def color_unstable(seeds: list, hit: np.ndarray) -> float:
    """Share of the hit pixels whose Diffuse Color differs between the seeds by more than 0.01 in some channel: the
    pixels whose "equal to Cycles" verdict could depend on the reference's seed."""
    d = np.abs(seeds[0]["Diffuse Color"][..., :3] - seeds[1]["Diffuse Color"][..., :3]).max(axis=-1)
    return round(float(np.mean(d[hit] > 0.01)), 6) if hit.any() else 0.0


def make(name: str, samples: int, out: str, force: bool) -> None:
    scene, frame, bounces = references.spec(name)
    references.build(name)
    fp = references.fingerprint()
    settings = ReferenceSettings(*RESOLUTION, samples=samples, bounces=bounces)
    _, meta_path = references.paths(name, out)
    if not force and os.path.exists(meta_path):
        old = references.load(name, out).meta
        if old.get("fingerprint") == fp and old.get("samples") == samples:
            print(f"{name}: up to date ({samples} spp), skipped", flush=True)
            return
    t0 = time.perf_counter()
    ref = render_reference(fp, settings, progress=lambda m: print(f"{name}: {m}", flush=True))
    wall = time.perf_counter() - t0
    missing = [p for p in references.PASSES + ("Depth",) if p not in ref.passes]
    if missing:
        raise SystemExit(f"{name}: Cycles wrote no {', '.join(missing)} pass (it wrote {', '.join(sorted(ref.passes))})")
    hit = ref.passes["Depth"][..., 0] < 1e9
    passes = {p: ref.passes[p][..., :3] for p in references.PASSES}
    passes["Depth"] = ref.passes["Depth"][..., :1]
    meta = {
        "scene": scene, "frame": frame, "fingerprint": fp,
        "description": scenes.USER_SCENES.get(name, ""),
        "samples": samples, "seeds": list(settings.seeds), "bounces": settings.bounces,
        "resolution": list(RESOLUTION),
        "cycles": {"device": "CPU", "adaptive_sampling": False, "denoising": False, "clamp_direct": 0,
                   "clamp_indirect": 0, "light_sampling_threshold": 0, "filter_width_px": 0.01,
                   "bounces_total_diffuse_glossy_transmission": settings.bounces, "volume_bounces": 0},
        "blender": bpy.app.version_string,
        "seconds": round(ref.seconds, 1), "wall_seconds": round(wall, 1), "cached": ref.cached,
        "storage": "two-seed mean, float16; Depth inf where Cycles hit nothing",
        "pixels_hit": int(hit.sum()),
        "noise_floor": floors(ref.seeds, hit),
        "diffuse_color_unstable": color_unstable(ref.seeds, hit),
        "made": datetime.date.today().isoformat(),
    }
    npz, _ = references.save(name, passes, meta, out)
    print(f"{name}: {samples} spp x 2 seeds in {ref.seconds:.0f} s (cached: {ref.cached}), "
          f"{os.path.getsize(npz) / 1024:.0f} KiB; noise floor "
          + ", ".join(f"{k} {v}" for k, v in meta["noise_floor"].items()), flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME")
    parser.add_argument("--samples", type=int, default=None,
                        help="per pixel and seed (default: references.default_samples, 1024 or 4096)")
    parser.add_argument("--force", action="store_true", help="render even where the files are up to date")
    parser.add_argument("--out", default=references.DIR)
    args = parser.parse_args(argv)
    names = args.names or references.names()
    unknown = [n for n in names if n not in references.names()]
    if unknown:
        parser.error(f"no reference for {' '.join(unknown)}; known: {' '.join(references.names())}")
    os.makedirs(args.out, exist_ok=True)
    for name in names:
        make(name, args.samples or references.default_samples(name), args.out, args.force)
    return 0


if __name__ == "__main__":
    sys.exit(main())
