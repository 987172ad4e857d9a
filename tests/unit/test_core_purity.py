# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels is the pure half (docs/architecture.md, One import direction): importing it, and every module in it, never pulls in bpy or mathutils.

The import check runs in a fresh interpreter so that nothing another test imported (bpy included) can hide or
fake a leak. The source grep catches imports hidden inside functions, which an import-time check cannot see.
"""
import json
import os
import re
import subprocess
import sys
import textwrap

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORE = os.path.join(ROOT, "gpu_kernels")
FORBIDDEN = ("bpy", "mathutils", "bmesh", "gpu", "bgl")
# Every module of the core, in its subpackages too, as paths relative to gpu_kernels/.
CORE_FILES = sorted(os.path.relpath(os.path.join(d, f), CORE) for d, _, files in os.walk(CORE) for f in files
                    if f.endswith(".py"))


def test_importing_every_gpu_kernels_module_loads_no_blender_module():
    code = textwrap.dedent("""
        import importlib, json, pkgutil, sys
        import bounce_gi.gpu_kernels as core
        names = ["bounce_gi.gpu_kernels"]
        for info in pkgutil.walk_packages(core.__path__, prefix="bounce_gi.gpu_kernels."):
            importlib.import_module(info.name)
            names.append(info.name)
        blender = sorted(m for m in sys.modules
                         if m.split(".")[0] in ("bpy", "mathutils", "bmesh", "gpu", "bgl", "_bpy"))
        print(json.dumps({"modules": names, "blender": blender}))
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    # The walk must really have imported the modules on disk (an empty walk would pass vacuously).
    on_disk = {f[:-3].replace(os.sep, ".").removesuffix(".__init__") for f in CORE_FILES if f != "__init__.py"}
    imported = {m[len("bounce_gi.gpu_kernels."):] for m in report["modules"][1:]}
    assert on_disk <= imported, f"not imported: {sorted(on_disk - imported)}"
    assert report["blender"] == [], f"gpu_kernels pulled in Blender modules: {report['blender']}"


_IMPORT_LINE = re.compile(r"^\s*(?:import\s+([\w., ]+)|from\s+([\w.]+)\s+import\b)", re.M)


def _imported_roots(text: str) -> set:
    roots = set()
    for m in _IMPORT_LINE.finditer(text):
        if m.group(1):
            for part in m.group(1).split(","):
                roots.add(part.strip().split(" ")[0].split(".")[0])
        else:
            roots.add(m.group(2).split(".")[0])
    return roots


def test_import_line_parser_catches_what_it_must():
    # The grep below is only as good as this parser: show that it sees the forms that matter.
    text = "import numpy as np\n    import bpy\nfrom mathutils import Vector\nimport os, bmesh\nfrom . import camera\n"
    assert {"bpy", "mathutils", "bmesh", "numpy", "os"} <= _imported_roots(text)


@pytest.mark.parametrize("name", CORE_FILES)
def test_gpu_kernels_source_never_imports_blender(name):
    with open(os.path.join(CORE, name), encoding="utf-8") as fh:
        text = fh.read()
    bad = _imported_roots(text) & set(FORBIDDEN)
    assert not bad, f"gpu_kernels/{name} imports {sorted(bad)}"
    # Also catch dynamic imports by name.
    assert not re.search(r"""(import_module|__import__)\(\s*["'](bpy|mathutils)""", text), name
