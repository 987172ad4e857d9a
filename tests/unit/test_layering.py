"""The layout's rules, read from the source (no imports run): no import cycles, no private names crossing
modules, one import direction inside the core and between the add-on's parts, and module and function sizes a
newcomer can read. Function-level imports count like top-level ones: a cycle hidden in a function is a cycle."""
import ast
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "bounce_gi"  # the repository root is the package (pyproject.toml: package-dir)
SOURCE_DIRS = ("gpu_kernels", "addon", "ui")  # the extension's code, under bounce_gi.*
SCRIPT_DIRS = ("benchmarks", "examples", "tools", "tests")  # imported by their own top-level names
# Inside the core, a module may import from its own package or from a lower rank: gl → common → direct → voxel →
# lpv | vct → settings, compose → pipeline → engine (scene and output are plain data and I/O, rank 0).
CORE_RANK = {"gl": 0, "scene": 0, "output": 0, "common": 1, "direct": 2, "voxel": 3, "lpv": 4, "vct": 4,
             "settings": 5, "compose": 5, "pipeline": 6, "engine": 7}
TOOLING = ("bounce_gi.addon.cli", "bounce_gi.addon.bench")  # left out of the extension zip
MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 60


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    if parts and parts[0] in SOURCE_DIRS or not parts:
        parts = [PACKAGE, *parts]
    return ".".join(parts)


def source_files() -> dict:
    files = {}
    for top in SOURCE_DIRS + SCRIPT_DIRS:
        for path in sorted((ROOT / top).rglob("*.py")):
            files[module_name(path)] = path
    files[PACKAGE] = ROOT / "__init__.py"
    return files


FILES = source_files()
MODULES = set(FILES)


def is_package(name: str) -> bool:
    return FILES.get(name, Path()).name == "__init__.py"


def resolve(current: str, level: int, module: str | None) -> str:
    """The absolute module an ImportFrom names (relative imports resolved against `current`)."""
    if level == 0:
        return module or ""
    base = current.split(".") if is_package(current) else current.split(".")[:-1]
    base = base[:len(base) - (level - 1)]
    return ".".join(base + ([module] if module else []))


def project(name: str) -> str | None:
    """`name` if it is one of the project's modules (the `bounce_gi` prefix added where imports omit it)."""
    for candidate in (name, f"{PACKAGE}.{name}"):
        if candidate in MODULES:
            return candidate
    return None


def analyse(name: str, path: Path):
    """(imported project modules, private-name uses as 'what (line)') of one module."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    edges, private, aliases = set(), [], {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                target = project(a.name)
                if target:
                    edges.add(target)
                    aliases[a.asname or a.name.split(".")[0]] = target if a.asname else project(a.name.split(".")[0])
        elif isinstance(node, ast.ImportFrom):
            base = resolve(name, node.level, node.module)
            target = project(base)
            for a in node.names:
                sub = project(f"{base}.{a.name}")
                if sub:
                    edges.add(sub)
                    aliases[a.asname or a.name] = sub
                elif target:
                    edges.add(target)
                    if a.name.startswith("_") and not a.name.startswith("__"):
                        private.append(f"from {base} import {a.name} (line {node.lineno})")
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases
                and node.attr.startswith("_") and not node.attr.startswith("__")):
            private.append(f"{node.value.id}.{node.attr} (line {node.lineno})")
    edges.discard(name)
    return edges, private


GRAPH, PRIVATE = {}, {}
for _name, _path in FILES.items():
    GRAPH[_name], PRIVATE[_name] = analyse(_name, _path)


def cycles(graph: dict) -> list:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


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
            if name.startswith(f"{PACKAGE}.addon") and target.startswith(f"{PACKAGE}.ui"):
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
    here = sys.modules[__name__]
    monkeypatch.setattr(here, "FILES", {"pkg.a": tmp_path / "pkg/a.py", "pkg.b": tmp_path / "pkg/b.py"})
    monkeypatch.setattr(here, "MODULES", {"pkg.a", "pkg.b"})
    assert analyse("pkg.a", tmp_path / "pkg" / "a.py") == ({"pkg.b"}, expected)


def test_cycle_check_catches_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_graph_is_not_empty():
    """Guards the checks above against vacuous passes (a path mistake that finds no files)."""
    assert len(FILES) > 60
    assert GRAPH[f"{PACKAGE}.gpu_kernels.pipeline"] >= {f"{PACKAGE}.gpu_kernels.settings",
                                                         f"{PACKAGE}.gpu_kernels.lpv.passes"}
    assert os.path.basename(FILES[f"{PACKAGE}.gpu_kernels.lpv"]) == "__init__.py"
