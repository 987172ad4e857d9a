# SPDX-License-Identifier: GPL-3.0-or-later
"""Write the example scenes as .blend files.

    python examples/build_examples.py OUTDIR [name ...]

Writes OUTDIR/<name>.blend for every scene in examples.scenes.SCENES (or only
the named ones), one printed line per file. Needs the `bpy` module.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from examples import scenes  # noqa: E402


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        print("scenes:", " ".join(scenes.SCENES))
        return 0 if argv else 2
    outdir, names = argv[0], argv[1:] or list(scenes.SCENES)
    unknown = [n for n in names if n not in scenes.SCENES]
    if unknown:
        print(f"unknown scene(s): {' '.join(unknown)}; known: {' '.join(scenes.SCENES)}", file=sys.stderr)
        return 2
    for name in names:
        path = scenes.save(name, os.path.join(outdir, name + ".blend"))
        print(f"{name}: {path}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
