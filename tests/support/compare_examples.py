# SPDX-License-Identifier: GPL-3.0-or-later
"""Render example scenes with Bounce GI and with Cycles (two seeds) and print one JSON line of errors.

Run in a subprocess by the `compare_examples` fixture (tests/conftest.py) for tests/accuracy/, so bpy's global state
stays out of the pytest process:
    python tests/support/compare_examples.py SAMPLES NAME [NAME...] [--method lpv|vct] [--bounces N]
                                             [--lpv KEY=VALUE ...] [--vct KEY=VALUE ...]
A NAME is an example scene (examples.scenes.SCENES) or a test scene as `module:function` (build below). SAMPLES is
Cycles' samples per pixel and seed of a reference rendered (or found in the cache) now, or `committed`: the scene's
committed reference against Cycles with --bounces bounces (examples/references TRANSPORT), never rendered here; it
must belong to the scene as built now (references.stale). Besides rel-L1 and noise floors, each report holds the
ratio Σ ours / Σ Cycles per compared pass.
"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", ".."))

from bounce_gi.addon.cli import compare  # noqa: E402
from bounce_gi.addon.extract import extract_scene  # noqa: E402
from examples import scenes  # noqa: E402

COMMITTED = "committed"  # SAMPLES: the committed reference instead of a Cycles render


def main():
    import bpy

    import argparse

    from bounce_gi.addon.cli import parse_method_options, vct_options

    parser = argparse.ArgumentParser()
    parser.add_argument("samples", type=lambda v: v if v == COMMITTED else int(v))
    parser.add_argument("names", nargs="+")
    parser.add_argument("--method", default="none")
    parser.add_argument("--bounces", type=int, default=8, help="Cycles bounces of the reference")
    parser.add_argument("--lpv", nargs="+", default=[])
    parser.add_argument("--vct", nargs="+", default=[])
    parser.add_argument("--snapshot", action="store_true",
                        help="also draw the viewport's view (bounce-gi snapshot) and compare its Combined")
    args = parser.parse_args()
    out = {}
    for name in args.names:
        if args.samples == COMMITTED:
            scene, (report, result, ref, mask) = compare_committed(name, args)
        else:
            build(name)
            scene = extract_scene(bpy.context.evaluated_depsgraph_get())
            report, result, ref, mask = compare(scene, args.method, args.samples, args.bounces,
                                                progress=lambda m: None, lpv_options=parse_method_options(args.lpv),
                                                vct_settings=vct_options(args.vct))
        if args.snapshot:
            add_snapshot(report, scene, args, result, ref, mask)
        add_ratios(report, result, ref, mask)
        report["dark_pixels"] = dark_pixels(result.passes["Diffuse Indirect"], ref.passes["Diffuse Indirect"], mask)
        out[name] = report
    sys.stdout.flush()
    print("RESULT " + json.dumps(out), flush=True)


def compare_committed(name, args):
    """(scene, (report, result, reference, mask)): ours against the committed reference of `name` with
    args.bounces bounces; exits with a message where the reference does not belong to the scene built now."""
    import bpy

    from bounce_gi.addon.cli import parse_method_options, render_ours, vct_options
    from bounce_gi.addon.reference.compare import compare_result
    from examples import references

    ref_name = references.transport_name(name, args.bounces)
    ref = references.load(ref_name)
    references.build(ref_name)
    why = references.stale(ref)
    if why:
        raise SystemExit(why)
    scene = extract_scene(bpy.context.evaluated_depsgraph_get())
    result = render_ours(scene, args.method, parse_method_options(args.lpv), vct_options(args.vct))
    report, mask = compare_result(scene, result, ref, args.method, ref.meta["samples"], args.bounces)
    return scene, (report, result, ref, mask)


def build(name):
    """An example scene by its name, or a test scene as `module:function` (e.g.
    `tests.support.emitter_scenes:lamp_room`, built by that module's build())."""
    if ":" not in name:
        scenes.build(name)
        return
    import importlib

    module, function = name.split(":", 1)
    importlib.import_module(module).build(function)


def add_ratios(report, result, ref, mask):
    """report["ratio"][key] = Σ ours / Σ Cycles over the compared pixels and channels, per compared pass: whether
    a pass is too bright or too dark in total, which rel-L1 alone does not say."""
    from bounce_gi.addon.reference.compare import COMPARED

    report["ratio"] = {}
    for pass_name, key in COMPARED:
        r = float(ref.passes[pass_name][mask][..., :3].sum())
        report["ratio"][key] = float(result.passes[pass_name][mask][..., :3].sum()) / r if r > 0 else float("nan")


def dark_pixels(ours, ref, mask, k: int = 5) -> int:
    """Pixels whose Diffuse Indirect (red) is below 0.4 × the k × k box mean of Cycles' around them: dark lines and
    spots (the LPV's junction seams) stand out of the reference's noise, which the box mean averages away."""
    import numpy as np

    r = np.pad(ref[..., 0], k // 2, mode="edge")
    smooth = sum(r[dy:dy + ref.shape[0], dx:dx + ref.shape[1]] for dy in range(k) for dx in range(k)) / (k * k)
    return int((mask & (ours[..., 0] < 0.4 * smooth)).sum())


def add_snapshot(report, scene, args, result, ref, mask):
    """report["rel_l1"]["snapshot_combined"] (against Cycles) and ["snapshot_vs_render"] (against our render)."""
    from bounce_gi.addon.cli.options import method_settings
    from bounce_gi.gpu_kernels.engine import get_engine
    from bounce_gi.gpu_kernels.output import metrics
    from bounce_gi.gpu_kernels.surface.atlas import VIEWPORT_TEXELS
    from bounce_gi.ui import draw

    settings = method_settings(scene, args.method, args.lpv, args.vct)
    light = get_engine().submit_surface(scene, settings, VIEWPORT_TEXELS).result()
    shot = draw.snapshot(light, scene, *scene.resolution)
    report["rel_l1"]["snapshot_combined"] = metrics.rel_l1(shot, ref.passes["Combined"], mask)
    report["rel_l1"]["snapshot_vs_render"] = metrics.rel_l1(shot, result.passes["Combined"], mask)


if __name__ == "__main__":
    main()
