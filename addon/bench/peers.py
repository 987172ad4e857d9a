# SPDX-License-Identifier: GPL-3.0-or-later
"""The peers `bounce-gi bench` measures on the same scene and resolution: Cycles at 1…256 samples (1…16 with
--quick) without and with OpenImageDenoise, and EEVEE at its defaults (its first render compiles shaders, so the
second is timed).

Peer times are bpy.ops.render.render wall time: scene sync, render and writing the EXR, as a user would wait.
Settings are changed inside `saved_attributes`, so the open scene is left as it was.
"""
from __future__ import annotations

import os
import time

from .scores import finite

EEVEE_QUICK_NOTE = ("skipped in --quick: EEVEE takes more than 60 s here (shader compilation + render on a "
                    "software GL; measured 22 s first and 68 s second render at 48x36); run without --quick")


def render_exr(bpy, path: str) -> tuple:
    from ...gpu_kernels.output import exr as exr_io

    bpy.context.scene.render.filepath = path
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - start
    return seconds, exr_io.read_passes(path)


def render_peers(ref, mask, width, height, quick, progress, tmp, eevee=True) -> tuple:
    """Cycles at a few sample counts without and with OIDN, then EEVEE; (peers, warnings)."""
    import bpy

    from ...gpu_kernels.output import metrics
    from ..reference.cycles import ReferenceSettings, configure_cycles, saved_attributes, settings_to_save

    scene, view_layer = bpy.context.scene, bpy.context.view_layer
    peers, warnings = [], []

    def score(passes):
        return finite(metrics.rel_l1(passes["Combined"], ref.passes["Combined"], mask))

    with saved_attributes(settings_to_save(scene, view_layer) + [(scene.cycles, "denoiser")]):
        path = os.path.join(tmp, "peer.exr")
        configure_cycles(scene, view_layer, ReferenceSettings(width, height, samples=1), 3, path)
        try:
            render_exr(bpy, path)  # warm-up: kernel load, first scene sync
        except Exception as exc:  # noqa: BLE001 — a peer failing must not end the benchmark
            warnings.append(f"Cycles warm-up failed: {exc}")
        for denoise in (False, True):
            for spp in ((1, 4, 16) if quick else (1, 4, 16, 64, 256)):
                entry = {"engine": "CYCLES", "samples": spp, "denoise": denoise, "seconds": None,
                         "rel_l1": {"combined": None}}
                progress(f"bench: Cycles {spp} spp" + (" + OIDN" if denoise else ""))
                try:
                    # seed 3: independent of the reference's seeds 1 and 2
                    configure_cycles(scene, view_layer, ReferenceSettings(width, height, samples=spp), 3, path)
                    scene.cycles.use_denoising = denoise
                    if denoise:
                        scene.cycles.denoiser = "OPENIMAGEDENOISE"
                    entry["seconds"], passes = render_exr(bpy, path)
                    entry["rel_l1"]["combined"] = score(passes)
                except Exception as exc:  # noqa: BLE001
                    entry["error"] = f"{type(exc).__name__}: {exc}"
                peers.append(entry)
    peers.append(render_eevee(bpy, width, height, quick or not eevee, progress, tmp, score, warnings))
    return peers, warnings


def render_eevee(bpy, width, height, skip, progress, tmp, score, warnings) -> dict:
    from ..reference.cycles import saved_attributes

    scene = bpy.context.scene
    r = scene.render
    engines = [e.identifier for e in type(r).bl_rna.properties["engine"].enum_items]
    name = next((e for e in ("BLENDER_EEVEE_NEXT", "BLENDER_EEVEE") if e in engines), None)
    entry = {"engine": name or "EEVEE", "samples": None, "denoise": False, "seconds": None,
             "rel_l1": {"combined": None}}
    if name is None:
        entry["error"] = f"no EEVEE engine in this Blender ({', '.join(engines)})"
        return entry
    entry["samples"] = getattr(getattr(scene, "eevee", None), "taa_render_samples", None)
    if skip:
        entry["error"] = EEVEE_QUICK_NOTE
        warnings.append(entry["error"])
        return entry
    im = r.image_settings
    attrs = [(r, a) for a in ("engine", "resolution_x", "resolution_y", "resolution_percentage", "use_border",
                              "film_transparent", "filepath")]
    attrs += [(im, "color_depth"), (im, "file_format")] + ([(im, "media_type")] if hasattr(im, "media_type") else [])
    with saved_attributes(attrs):
        r.engine = name
        r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
        r.use_border, r.film_transparent = False, False
        if hasattr(im, "media_type"):
            im.media_type = "MULTI_LAYER_IMAGE"
        im.file_format, im.color_depth = "OPEN_EXR_MULTILAYER", "32"
        path = os.path.join(tmp, "eevee.exr")
        try:
            progress("bench: EEVEE first render (compiles shaders)")
            entry["first_render_seconds"], _ = render_exr(bpy, path)
            progress("bench: EEVEE second render (timed)")
            entry["seconds"], passes = render_exr(bpy, path)
            entry["rel_l1"]["combined"] = score(passes)
        except Exception as exc:  # noqa: BLE001
            entry["error"] = f"{type(exc).__name__}: {exc}"
    return entry
