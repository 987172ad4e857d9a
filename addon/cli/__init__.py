# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi`: render a .blend with Bounce GI, or compare it with a Cycles reference, from the command line.

Runs Blender as a Python module (bpy), so it works in background batch jobs. Bad input gives one line on stderr
and exit code 2; nothing is written unless the whole render succeeded.

The subcommands live in render.py, compare.py and bench_command.py (the benchmark itself: addon/bench/), the
method-settings options in options.py, the input and output checks in addon/scene_io.py. Developer tooling: not
part of the extension zip, and nothing in the add-on or the UI imports it.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from ..scene_io import CliError, check_blend_path, load_scene
from .bench_command import cmd_bench
from .compare import cmd_compare, compare, format_compare
from .options import parse_method_options, render_ours, vct_options
from .render import cmd_render, format_timings
from ...gpu_kernels.surface.atlas import VIEWPORT_TEXELS
from .snapshot import cmd_snapshot

SNAPSHOT_TEXELS = VIEWPORT_TEXELS  # what the viewport's final stage uses

__all__ = ["main", "build_parser", "CliError", "check_blend_path", "load_scene", "compare", "format_compare",
           "format_timings", "parse_method_options", "render_ours", "vct_options"]

EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 1


class _ArgumentParser(argparse.ArgumentParser):
    """argparse, but a usage error is one line on stderr and exit code 2 like every other bad input."""

    def error(self, message):
        self.exit(EXIT_BAD_INPUT, f"bounce-gi: error: {message} (see bounce-gi --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from ...gpu_kernels.settings import METHODS

    parser = _ArgumentParser(prog="bounce-gi", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a .blend from its scene camera into a multi-layer EXR")
    r.add_argument("scene")
    r.add_argument("--method", choices=METHODS, help="default: none (with --budget-ms/--target-error: chosen)")
    r.add_argument("--res", nargs=2, type=int, metavar=("W", "H"))
    r.add_argument("--out", help="output .exr (default: next to the .blend); with several --frames, #### in the "
                                 "name becomes the frame number, e.g. DIR/frame_####.exr")
    r.add_argument("--frames", metavar="A-B", help="render frames A to B (the animation as keyed), one EXR a frame, "
                                                   "reusing what an unchanged input allows between frames")
    r.add_argument("--budget-ms", type=float, metavar="MS",
                   help="choose method and settings: the most accurate measured to fit this frame time")
    r.add_argument("--target-error", type=float, metavar="E",
                   help="choose method and settings: the fastest measured to reach this Combined rel-L1")
    r.add_argument("--json", action="store_true", help="print one JSON object as the last stdout line")
    r.add_argument("--lpv", nargs="+", metavar="KEY=VALUE", help="LPV settings, e.g. bounces=4 resolution=32")
    r.add_argument("--vct", nargs="+", metavar="KEY=VALUE", help="VCT settings, e.g. bounces=4 resolution=64")
    r.set_defaults(func=cmd_render)
    c = sub.add_parser("compare", help="render and compare with a two-seed Cycles reference (cached)")
    c.add_argument("scene")
    c.add_argument("--method", choices=METHODS, default="none")
    c.add_argument("--samples", type=int, default=256)
    c.add_argument("--bounces", type=int, default=8, help="Cycles bounce count of the reference")
    c.add_argument("--res", nargs=2, type=int, metavar=("W", "H"))
    c.add_argument("--json", action="store_true")
    c.add_argument("--heatmap", help="write a per-pixel relative error heat map (PNG)")
    c.add_argument("--lpv", nargs="+", metavar="KEY=VALUE", help="LPV settings, e.g. bounces=4 resolution=32")
    c.add_argument("--vct", nargs="+", metavar="KEY=VALUE", help="VCT settings, e.g. bounces=4 resolution=64")
    c.set_defaults(func=cmd_compare)
    s = sub.add_parser("snapshot", help="draw the scene camera's view as the viewport does (EXR or PNG)")
    s.add_argument("scene")
    s.add_argument("--method", choices=METHODS, help="default: none")
    s.add_argument("--res", nargs=2, type=int, metavar=("W", "H"))
    s.add_argument("--out", required=True, help="output .exr (a Combined layer, scene-linear) or .png")
    s.add_argument("--display", choices=("combined", "indirect", "direct"), default="combined")
    s.add_argument("--texels", type=int, default=SNAPSHOT_TEXELS, metavar="N",
                   help=f"surface atlas texels per page (default {SNAPSHOT_TEXELS})")
    s.add_argument("--json", action="store_true", help="print one JSON object as the last stdout line")
    s.add_argument("--lpv", nargs="+", metavar="KEY=VALUE", help="LPV settings, e.g. bounces=4 resolution=32")
    s.add_argument("--vct", nargs="+", metavar="KEY=VALUE", help="VCT settings, e.g. bounces=4 resolution=64")
    s.set_defaults(func=cmd_snapshot)
    b = sub.add_parser("bench", help="time vs error of our settings, Cycles (± OIDN) and EEVEE; plots, summary.md")
    b.add_argument("scenes", nargs="*", metavar="SCENE")
    b.add_argument("--quick", action="store_true", help="few settings, 96x72, 64-spp reference, one timed run")
    b.add_argument("--res", nargs=2, type=int, metavar=("W", "H"))
    b.add_argument("--out", help="directory for plots, summary.md, quality_front.json (default: ./bounce-gi-bench)")
    b.add_argument("--json", action="store_true")
    b.add_argument("--incremental", action="store_true", help="time updates by kind of edit in one engine")
    b.add_argument("--methods", nargs="+", choices=("none", "lpv", "vct"), default=["none", "lpv", "vct"],
                   help="with --incremental: the methods to time (default: all)")
    b.add_argument("--scaling", action="store_true", help="time against triangles, grid size and resolution")
    b.add_argument("--no-eevee", action="store_true", help="skip the EEVEE peer (minutes on a software GL)")
    b.set_defaults(func=cmd_bench)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (exit 0) or a usage error already printed as one line (exit 2)
        return int(exc.code) if exc.code else 0
    try:
        if args.res and (args.res[0] < 1 or args.res[1] < 1):
            raise CliError("--res needs two positive integers")
        if getattr(args, "texels", 1) < 1:
            raise CliError("--texels must be at least 1")
        if getattr(args, "samples", 1) < 1:
            raise CliError("--samples must be at least 1")
        report = args.func(args)
    except CliError as exc:
        print(f"bounce-gi: error: {exc}", file=sys.stderr, flush=True)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("bounce-gi: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # never a traceback for the user; BOUNCE_GI_DEBUG=1 shows it
        if os.environ.get("BOUNCE_GI_DEBUG"):
            raise
        print(f"bounce-gi: internal error: {type(exc).__name__}: {exc} (set BOUNCE_GI_DEBUG=1 for details)",
              file=sys.stderr, flush=True)
        return EXIT_INTERNAL
    if args.json:
        sys.stdout.flush()
        print(json.dumps(report, default=float), flush=True)
    return 0
