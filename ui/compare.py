# SPDX-License-Identifier: GPL-3.0-or-later
"""The steps of "Compare with Cycles" (`bounce_gi.compare_cycles`, compare_operator.py) as plain functions, and the
runtime state of the last comparison: the CLI's `bounce-gi compare`, inside Blender.

start_compare() extracts the scene at the preview size and submits our render to the engine (it runs on the GPU
thread while Cycles renders), and prepares the two-seed Cycles reference (addon/reference/cycles.ReferenceJob; from
the cache when it has it). The operator then renders the reference seed by seed — Blender's own render job when
interactive, `bpy.ops.render.render` blocking in background mode (run_reference_blocking) — and finish_compare()
compares (addon/reference/compare.py), fills three Image Editor images (ours, Cycles, the error heat map) and keeps
the report for the panel. The scene's render settings are snapshotted before the first seed and restored exactly
after the last (or after a cancel or a failure): addon/reference/settings_snapshot.py.
"""
from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import preview
from .preview import PreviewError

IMAGES = {"ours": "Bounce GI Compare: Ours", "cycles": "Bounce GI Compare: Cycles",
          "error": "Bounce GI Compare: Error"}
REFERENCE_BOUNCES = 8  # Cycles' bounce count: what our methods' 8 bounces are measured against
ERROR_MAP_MAX = 0.5  # relative error shown white in the heat map (metrics.heatmap_rgb8's ramp)
PASS_LABELS = {"combined": "Combined", "diffuse_direct": "Diffuse Direct", "diffuse_indirect": "Diffuse Indirect",
               "glossy_direct": "Glossy Direct", "glossy_indirect": "Glossy Indirect"}


@dataclass
class CompareState:
    """Module-level state, deliberately not a bpy property: it must never be saved in a .blend."""
    busy: bool = False
    last: dict | None = None  # the report of the last finished comparison (addon/reference/compare.py)
    last_error: str | None = None
    status: str = ""  # what a running comparison is doing, for the panel
    timer: object | None = None  # the modal operator's window-manager timer, removed on unregister
    job: object | None = None  # the running CompareJob (unregister restores its render settings)


state = CompareState()


@bpy.app.handlers.persistent
def forget_last_compare(_dummy=None) -> None:
    """load_post handler: another file's errors would mislead."""
    state.last, state.last_error, state.status = None, None, ""


@dataclass
class CompareJob:
    """Our render (submitted) and the Cycles reference (seed by seed) of one comparison."""
    pending: preview.PendingRender
    reference: object  # addon.reference.cycles.ReferenceJob
    samples: int
    started: float = field(default_factory=time.perf_counter)

    def elapsed(self) -> float:
        return time.perf_counter() - self.started


def start_compare(context) -> CompareJob:
    """Extract and submit our render at the preview size; prepare the reference of the same view and size."""
    from ..addon.reference.cycles import ReferenceJob, ReferenceSettings

    scene = context.scene
    settings = scene.bounce_gi
    size = preview.preview_resolution(scene, settings.resolution_percentage)
    pending = preview.submit_scene(context.evaluated_depsgraph_get(), size)
    ref_settings = ReferenceSettings(pending.width, pending.height, samples=settings.compare_samples,
                                     bounces=REFERENCE_BOUNCES)
    reference = ReferenceJob(pending.scene_data.content_hash(), ref_settings, scene, context.view_layer)
    return CompareJob(pending, reference, settings.compare_samples)


def run_reference_blocking(job: CompareJob) -> None:
    """Background mode and scripts: render the reference's seeds now (render settings restored afterwards)."""
    from ..addon.reference.cycles import run_blocking

    if job.reference.cached is None:
        try:
            job.reference.cached = run_blocking(job.reference)
        except Exception as ex:  # the console gets the traceback, the user one line
            traceback.print_exc()
            raise PreviewError(f"Cycles reference render failed: {preview.one_line(ex)}") from None


def finish_compare(job: CompareJob, reference) -> dict:
    """Wait for our render, compare it with `reference` (a cycles.Reference), write the three images, keep and
    return the report."""
    from ..addon.reference.compare import compare_result, error_map
    from ..gpu_kernels.output import metrics

    result = preview.wait_result(job.pending)
    scene_data = job.pending.scene_data
    report, mask = compare_result(scene_data, result, reference, job.pending.method, job.samples,
                                  REFERENCE_BOUNCES)
    report["warnings"] = list(dict.fromkeys([*job.pending.scene_warnings, *report["warnings"]]))
    report["wall_seconds"] = job.elapsed()
    preview.write_preview_image(result.passes["Combined"], IMAGES["ours"])
    preview.write_preview_image(reference.passes["Combined"], IMAGES["cycles"])
    heat = metrics.heatmap_rgb8(error_map(result, reference, mask), vmax=ERROR_MAP_MAX)
    write_display_image(heat, IMAGES["error"])
    state.last, state.last_error, state.status = report, None, ""
    return report


def write_display_image(rgb8: np.ndarray, name: str):
    """An (H, W, 3) uint8 picture (display values, rows top-to-bottom) as a Non-Color float image, so the Image
    Editor shows its colours as they are, with no view transform (the heat map's ramp is not a radiance)."""
    values = rgb8.astype(np.float32) / 255.0
    img = preview.write_preview_image(values, name)
    if img.colorspace_settings.name != "Non-Color":
        img.colorspace_settings.name = "Non-Color"  # this refills a generated image's buffer: write it again
        img = preview.write_preview_image(values, name)
    return img


def summary(report: dict) -> str:
    """One line for self.report: rel-L1 per pass and the reference's noise."""
    errors = ", ".join(f"{PASS_LABELS[k]} {v:.3f}" for k, v in report["rel_l1"].items())
    floor = max(report["noise_floor"].values())
    return (f"Bounce GI vs Cycles ({report['reference']['samples']} spp x 2): rel-L1 {errors} "
            f"(Cycles' own noise <= {floor:.3f})")


def cancel(job: CompareJob | None) -> None:
    """Stop a comparison: drop our render if it has not started, restore the render settings."""
    if job is None:
        return
    job.pending.future.cancel()
    job.reference.restore()
