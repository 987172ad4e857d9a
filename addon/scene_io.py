# SPDX-License-Identifier: GPL-3.0-or-later
"""Input and output checks shared by the developer tools (`bounce-gi` in addon/cli/, its benchmark in addon/bench/):
open a .blend and extract its Scene, check output paths before anything renders, write files, and the one error
type they raise for bad input.

Imports nothing of addon/cli or addon/bench (both import this), and bpy only inside `load_scene`.
"""
from __future__ import annotations

import os
import sys
import tempfile

BLEND_MAGICS = (b"BLENDER", b"\x1f\x8b", b"\x28\xb5\x2f\xfd")  # plain, gzip, zstd-compressed .blend


class CliError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


def progress(message: str) -> None:
    print(f"bounce-gi: {message}", file=sys.stderr, flush=True)


def check_blend_path(path: str) -> str:
    if not os.path.exists(path):
        raise CliError(f"{path}: no such file")
    if os.path.isdir(path):
        raise CliError(f"{path}: is a directory, not a .blend file")
    try:
        with open(path, "rb") as f:
            head = f.read(7)
    except OSError as exc:
        raise CliError(f"{path}: cannot read ({exc.strerror})") from None
    if not any(head.startswith(m) for m in BLEND_MAGICS):
        raise CliError(f"{path}: not a .blend file")
    return os.path.abspath(path)


def check_output_path(path: str, suffix: str) -> str:
    """Fail before rendering if the output cannot be written."""
    if not path.lower().endswith(suffix):
        raise CliError(f"{path}: output must be a {suffix} file")
    path = os.path.abspath(path)
    parent = os.path.dirname(path)
    if os.path.isdir(path):
        raise CliError(f"{path}: is a directory")
    if os.path.exists(parent) and not os.path.isdir(parent):
        raise CliError(f"{path}: {parent} is not a directory")
    if not os.path.isdir(parent):
        raise CliError(f"{path}: directory {parent} does not exist")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise CliError(f"{path}: not writable")
    # os.access() says yes to root even where nothing can be created (procfs, read-only mounts): try it.
    try:
        fd, probe = tempfile.mkstemp(prefix=".bounce-gi-probe-", dir=parent)
    except OSError as exc:
        raise CliError(f"{path}: not writable ({exc.strerror})") from None
    os.close(fd)
    os.unlink(probe)
    return path


def check_out_dir(path: str) -> str:
    """An output directory (`bench --out`): created if missing; CliError if it cannot be written."""
    path = os.path.abspath(path)
    if os.path.exists(path) and not os.path.isdir(path):
        raise CliError(f"--out {path}: exists and is not a directory")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise CliError(f"--out {path}: cannot create it ({exc.strerror})") from None
    if not os.access(path, os.W_OK):
        raise CliError(f"--out {path}: not writable")
    return path


def write_output(writer, path: str, *args) -> None:
    """Run an image writer; a failure (disk full, permissions changed meanwhile) is a one-line user error."""
    try:
        writer(path, *args)
    except OSError as exc:
        raise CliError(f"{path}: cannot write ({exc})") from None


def write_text_atomic(path: str, text: str) -> None:
    """Write through a temporary file, so an interrupted run never leaves a half-written file."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def load_scene(path: str, resolution=None):
    """Open a .blend with bpy and extract its Scene; raise CliError for scenes that cannot be rendered."""
    path = open_blend(path)
    return extract_open_scene(path, resolution)


def open_blend(path: str) -> str:
    """Open a .blend with bpy (its absolute path back); CliError when it is not one or Blender cannot read it."""
    import bpy

    path = check_blend_path(path)
    try:
        bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
    except RuntimeError as exc:
        raise CliError(f"{path}: Blender could not open it ({str(exc).strip().splitlines()[-1]})") from None
    return path


def extract_open_scene(path: str, resolution=None):
    """Extract the Scene of the open .blend at its current frame; CliError (naming `path`) for scenes that cannot
    be rendered."""
    import bpy

    from .extract import ExtractError, extract_scene

    try:
        scene = extract_scene(bpy.context.evaluated_depsgraph_get(), resolution)
    except ExtractError as exc:
        raise CliError(f"{path}: {exc}") from None
    if not scene.lights and not scene.has_emission() and max(scene.world.color[:3]) <= 0:
        # The world is a light too: a room lit by its sky alone renders (as in Cycles).
        raise CliError(f"{path}: the scene has no lights and no emissive materials and its world is black, so it "
                       "would render black")
    if scene.triangle_count == 0:
        raise CliError(f"{path}: the scene has no visible geometry")
    return scene
