# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi bench`: time and error of our methods against Cycles (± OIDN) and EEVEE, in the order a run goes:

- sweep.py: the settings each method is benched at, and how rows are named;
- timing.py, scores.py: one row's frame time and its errors against the reference;
- peers.py: Cycles at a few sample counts without and with OIDN, and EEVEE, on the same scene;
- run.py: a whole run (every scene, then the files);
- front.py: Pareto front and speed-ups at equal error; report.py: summary.md and the quality table automatic
  quality reads (addon/quality.py); plot.py: the log-log plot (matplotlib, a bench-only dependency);
- incremental.py (`--incremental`), scaling.py (`--scaling`).

Developer tooling, driven by addon/cli/ (which imports this package, never the other way round); not part of the
extension zip. Shared input checks come from addon/scene_io.py.
"""
