# SPDX-License-Identifier: GPL-3.0-or-later
"""The layout's rules, read from the source (no imports run): no import cycles, no private names crossing
modules, one import direction inside the core and between the add-on's parts, and module and function sizes a
newcomer can read. Function-level imports count like top-level ones: a cycle hidden in a function is a cycle."""
import ast
import os

import pytest

from support import import_graph as ig
from support.import_graph import FILES, GRAPH, MODULES, PACKAGE, PRIVATE, ROOT, analyse, cycles

# Inside the core, a module may import from its own package or from a lower rank: gl → common → direct → voxel →
# lpv | vct → settings, compose → pipeline → engine (scene and output are plain data and I/O, rank 0).
CORE_RANK = {"gl": 0, "scene": 0, "output": 0, "common": 1, "direct": 2, "voxel": 3, "surface": 3, "lpv": 4, "vct": 4,
             "settings": 5, "compose": 5, "pipeline": 6, "engine": 7}
TOOLING = ("bounce_gi.addon.cli", "bounce_gi.addon.bench", "bounce_gi.addon.scene_io")  # left out of the zip
MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 60


def test_no_import_cycles():
    assert cycles(GRAPH) == []


def test_no_private_names_cross_modules():
    found = {name: uses for name, uses in PRIVATE.items() if uses}
    assert found == {}


def core_rank(name: str):
    parts = name.split(".")
    if parts[:2] != [PACKAGE, "gpu_kernels"] or len(parts) < 3:
        return None
    return parts[2], CORE_RANK[parts[2]]


def test_every_core_module_has_a_rank():
    unranked = [n for n in MODULES if n.startswith(f"{PACKAGE}.gpu_kernels.") and n.split(".")[2] not in CORE_RANK]
    assert unranked == []


def test_core_imports_point_down_the_pipeline():
    wrong = []
    for name, edges in GRAPH.items():
        here = core_rank(name)
        for target in edges:
            if name.startswith(f"{PACKAGE}.gpu_kernels") and not target.startswith(f"{PACKAGE}.gpu_kernels"):
                wrong.append(f"{name} → {target} (the core imports nothing outside it)")
            there = core_rank(target)
            if here and there and here[0] != there[0] and there[1] >= here[1]:
                wrong.append(f"{name} → {target}")
    assert wrong == []


def test_addon_and_ui_import_in_one_direction():
    wrong = []
    for name, edges in GRAPH.items():
        for target in edges:
            # The tooling sits above everything: `bounce-gi snapshot` draws with the UI's own drawing path.
            if name.startswith(f"{PACKAGE}.addon") and not name.startswith(TOOLING) \
                    and target.startswith(f"{PACKAGE}.ui"):
                wrong.append(f"{name} → {target}")
            shipped = name.startswith((f"{PACKAGE}.addon", f"{PACKAGE}.ui")) and not name.startswith(TOOLING)
            if shipped and target.startswith(TOOLING):
                wrong.append(f"{name} → {target} (developer tooling is not in the extension zip)")
    assert wrong == []


def test_modules_and_functions_fit_a_screen():
    long_modules, long_functions = [], []
    for name, path in FILES.items():
        text = path.read_text(encoding="utf-8")
        if len(text.splitlines()) > MAX_MODULE_LINES:
            long_modules.append(f"{path.relative_to(ROOT)}: {len(text.splitlines())}")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long_functions.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}: {n}")
    assert (long_modules, long_functions) == ([], [])


@pytest.mark.parametrize("source, expected", [
    ("from .b import _x\n", ["from pkg.b import _x (line 1)"]),
    ("from . import b\nb._y()\n", ["b._y (line 2)"]),
    ("from .b import x, __version__\nx.__name__\n", []),
])
def test_private_name_check_catches_what_it_must(tmp_path, monkeypatch, source, expected):
    """The checker itself: a private import and a private attribute of an imported module are found; public and
    dunder names are not."""
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "a.py").write_text(source)
    (tmp_path / "pkg" / "b.py").write_text("x = 1\n")
    monkeypatch.setattr(ig, "FILES", {"pkg.a": tmp_path / "pkg/a.py", "pkg.b": tmp_path / "pkg/b.py"})
    monkeypatch.setattr(ig, "MODULES", {"pkg.a", "pkg.b"})
    assert analyse("pkg.a", tmp_path / "pkg" / "a.py") == ({"pkg.b"}, expected)


def test_cycle_check_catches_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_graph_is_not_empty():
    """Guards the checks above against vacuous passes (a path mistake that finds no files)."""
    assert len(FILES) > 60
    assert GRAPH[f"{PACKAGE}.gpu_kernels.pipeline"] >= {f"{PACKAGE}.gpu_kernels.settings",
                                                         f"{PACKAGE}.gpu_kernels.lpv.passes"}
    assert os.path.basename(FILES[f"{PACKAGE}.gpu_kernels.lpv"]) == "__init__.py"


def test_every_source_file_states_its_licence():
    """The SPDX header (GPL-3.0-or-later, as LICENSE, the manifest and pyproject say) on every Python and GLSL file."""
    shaders = sorted((ROOT / "gpu_kernels" / "shaders").rglob("*.glsl"))
    missing = [str(p.relative_to(ROOT)) for p in list(FILES.values()) + shaders
               if "SPDX-License-Identifier: GPL-3.0-or-later" not in p.read_text(encoding="utf-8")[:200]]
    assert shaders and missing == []
