# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi render SCENE.blend --frames A-B [--out DIR/frame_####.exr]`: an animation, one multi-layer EXR a frame.

Every frame is extracted at its own time (objects, lights, camera and materials as animated) and rendered by the one
process-wide engine, whose pass cache re-runs a pass only when its inputs changed: a frame where only the light moved
reuses the geometry, textures and G-buffer of the frame before. Each frame gets a progress line on stderr (a bar,
its seconds and the passes it reused); the report lists per-frame seconds and reused passes.

Output names follow Blender's: the last run of `#` in the file name becomes the frame number, zero-padded to as
many digits as there are `#`. Each file is written whole (through a temporary file) as soon as its frame is done,
so an interrupted range leaves complete frames only.
"""
from __future__ import annotations

import os
import re
import time

from ..scene_io import CliError, check_blend_path, check_output_path, extract_open_scene, open_blend, progress, \
    write_output
from .options import parse_method_options, render_ours, vct_options

FRAMES_PATTERN = re.compile(r"^(-?\d+)(?:-(-?\d+))?$")
HASHES = re.compile(r"#+")
BAR_WIDTH = 20


def parse_frames(text: str) -> range:
    """`A-B` (or a single frame `A`) → range(A, B + 1); CliError for anything else or B < A."""
    match = FRAMES_PATTERN.match(text.strip())
    if not match:
        raise CliError(f"--frames {text}: expected A-B (first and last frame, e.g. 1-24) or one frame number")
    first = int(match.group(1))
    last = int(match.group(2)) if match.group(2) is not None else first
    if last < first:
        raise CliError(f"--frames {text}: the last frame ({last}) comes before the first ({first})")
    return range(first, last + 1)


def frame_path(pattern: str, frame: int) -> str:
    """The file of `frame`: the last run of `#` in the file name replaced by the zero-padded frame number (Blender's
    rule); the pattern itself when it has none."""
    directory, name = os.path.split(pattern)
    runs = list(HASHES.finditer(name))
    if not runs:
        return pattern
    run = runs[-1]
    digits = f"{abs(frame):0{len(run.group())}d}"
    return os.path.join(directory, name[:run.start()] + ("-" if frame < 0 else "") + digits + name[run.end():])


def output_pattern(args, frames: range) -> str:
    """The checked output pattern: --out, or `<blend>_bounce_<method>_####.exr` next to the .blend. CliError for
    several frames without `#` in the file name (they would overwrite each other) or an unwritable place."""
    if args.out:
        pattern = args.out
    else:
        check_blend_path(args.scene)
        pattern = os.path.splitext(os.path.abspath(args.scene))[0] + f"_bounce_{args.method}_####.exr"
    if len(frames) > 1 and not HASHES.search(os.path.basename(pattern)):
        raise CliError(f"--out {pattern}: {len(frames)} frames need #### in the file name for the frame number "
                       "(e.g. DIR/frame_####.exr)")
    check_output_path(frame_path(pattern, frames[0]), ".exr")
    return os.path.abspath(pattern)


def progress_line(index: int, count: int, record: dict) -> str:
    done = round(BAR_WIDTH * (index + 1) / count)
    reused = ", ".join(record["skipped"]) or "nothing"
    return (f"[{'#' * done}{'-' * (BAR_WIDTH - done)}] {index + 1}/{count} frame {record['frame']}: "
            f"{record['seconds']:.2f} s (extract {record['extract_seconds']:.2f}, render "
            f"{record['render_seconds']:.2f}); reused {reused}")


def render_frames(args, quality) -> dict:
    """Render every frame of --frames into its own EXR through one engine; the report (see the module docstring)."""
    frames = parse_frames(args.frames)
    pattern = output_pattern(args, frames)
    path = open_blend(args.scene)
    import bpy

    from ...gpu_kernels.output import exr as exr_io

    lpv, vct = parse_method_options(args.lpv), vct_options(args.vct)
    resolution = tuple(args.res) if args.res else None
    records, warnings, result = [], [], None
    for index, frame in enumerate(frames):
        start = time.perf_counter()
        bpy.context.scene.frame_set(frame)
        scene = extract_open_scene(path, resolution)
        extracted = time.perf_counter()
        result = render_ours(scene, args.method, lpv, vct)
        out = frame_path(pattern, frame)
        write_output(exr_io.write_passes, out, result.passes)
        record = {"frame": frame, "seconds": time.perf_counter() - start, "extract_seconds": extracted - start,
                  "render_seconds": result.timings.get("total", 0.0), "skipped": list(result.skipped),
                  "passes": {k: round(v, 6) for k, v in result.timings.items() if k != "total"}, "output": out}
        records.append(record)
        warnings += [w for w in [*scene.warnings, *result.warnings] if w not in warnings]
        progress(progress_line(index, len(frames), record))
    report = {"method": result.method, "resolution": list(result.resolution), "frames": records,
              "seconds": frame_seconds(records), "info": result.info, "scene": result.statistics,
              "warnings": warnings, "output": pattern}
    if quality:
        report["quality"] = quality
    if not args.json:
        print(format_frames(records))
        for w in warnings:
            print(f"warning: {w}")
        print(f"wrote {len(records)} frame{'s' if len(records) > 1 else ''} to {pattern}")
    return report


def frame_seconds(records: list) -> dict:
    """Total, first-frame and mean later-frame seconds (the later frames are where reuse shows)."""
    later = [r["seconds"] for r in records[1:]]
    return {"total": sum(r["seconds"] for r in records), "first_frame": records[0]["seconds"],
            "later_frames_mean": sum(later) / len(later) if later else None}


def format_frames(records: list) -> str:
    lines = [f"{'frame':>6}{'s':>9}{'render ms':>11}  reused passes"]
    for r in records:
        lines.append(f"{r['frame']:>6}{r['seconds']:>9.3f}{r['render_seconds'] * 1000:>11.1f}  "
                     f"{', '.join(r['skipped']) or '-'}")
    return "\n".join(lines)
