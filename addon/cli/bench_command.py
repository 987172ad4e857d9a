# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi bench`: the benchmark (addon/bench/) from the command line; time and error of our settings vs Cycles
(± OIDN) and EEVEE, or `--incremental` (cost of one update per kind of edit), or `--scaling`."""
from __future__ import annotations

import os

from ..bench.incremental import format_incremental, run_incremental
from ..bench.report import format_bench
from ..bench.run import run_bench
from ..bench.scaling import format_scaling, run_scaling
from ..scene_io import CliError, check_blend_path, check_out_dir, progress, write_output


def cmd_bench(args) -> dict:
    """Time and error of our settings vs Cycles (± OIDN) and EEVEE; or --incremental / --scaling."""
    if args.scaling:
        report = {"scaling": run_scaling(args.quick, progress)}
        if not args.json:
            print(format_scaling(report["scaling"]))
        return report
    if not args.scenes:
        raise CliError("bench needs at least one .blend (or --scaling)")
    if args.incremental:
        return bench_incremental(args)
    report = run_bench(args.scenes, args.quick, args.res, args.out, progress, eevee=not args.no_eevee)
    if not args.json:
        print(format_bench(report))
    return report


INCREMENTAL_FILE = "incremental_run.md"  # what `bench --incremental --out DIR` writes in DIR


def bench_incremental(args) -> dict:
    paths = [check_blend_path(p) for p in args.scenes]
    report = {"incremental": [run_incremental(p, args.res, tuple(args.methods), progress,
                                              1 if args.quick else 3) for p in paths]}
    if args.out:  # this run's tables; the results folder's incremental.md is the written-up history beside them
        text = "".join(format_incremental(e) for e in report["incremental"])
        write_output(lambda path, t: open(path, "w").write(t),
                     os.path.join(check_out_dir(args.out), INCREMENTAL_FILE), text)
    if not args.json:
        print("".join(format_incremental(e) for e in report["incremental"]))
    return report
