# SPDX-License-Identifier: GPL-3.0-or-later
"""Render example scenes with Bounce GI and with Cycles (two seeds) and print one JSON line of errors.

Run in a subprocess by the `compare_examples` fixture (tests/conftest.py) for tests/accuracy/, so bpy's global state
stays out of the pytest process:
    python tests/support/compare_examples.py SAMPLES NAME [NAME...] [--method lpv|vct] [--bounces N]
                                             [--lpv KEY=VALUE ...] [--vct KEY=VALUE ...]
"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", ".."))

from bounce_gi.addon.cli import compare  # noqa: E402
from bounce_gi.addon.extract import extract_scene  # noqa: E402
from examples import scenes  # noqa: E402


def main():
    import bpy

    import argparse

    from bounce_gi.addon.cli import parse_method_options, vct_options

    parser = argparse.ArgumentParser()
    parser.add_argument("samples", type=int)
    parser.add_argument("names", nargs="+")
    parser.add_argument("--method", default="none")
    parser.add_argument("--bounces", type=int, default=8, help="Cycles bounces of the reference")
    parser.add_argument("--lpv", nargs="+", default=[])
    parser.add_argument("--vct", nargs="+", default=[])
    args = parser.parse_args()
    out = {}
    for name in args.names:
        scenes.build(name)
        scene = extract_scene(bpy.context.evaluated_depsgraph_get())
        report, *_ = compare(scene, args.method, args.samples, args.bounces, progress=lambda m: None,
                             lpv_options=parse_method_options(args.lpv), vct_settings=vct_options(args.vct))
        out[name] = report
    sys.stdout.flush()
    print("RESULT " + json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
