# SPDX-License-Identifier: GPL-3.0-or-later
"""The project's import graph, read from the source (no module is imported): which project modules each module
imports (function-level imports included) and which private names of other modules it uses. Used by
tests/unit/test_layering.py (the layout's rules) and tests/blender/test_package.py (what the zip must hold)."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "bounce_gi"  # the repository root is the package (pyproject.toml: package-dir)
SOURCE_DIRS = ("gpu_kernels", "addon", "ui")  # the extension's code, under bounce_gi.*
SCRIPT_DIRS = ("benchmarks", "examples", "tools", "tests")  # imported by their own top-level names


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


def reachable(start: str) -> set:
    """Every project module importing `start` runs (its imports, theirs, …, and the packages that hold them)."""
    seen, stack = set(), [start]
    while stack:
        name = stack.pop()
        if name in seen:
            continue
        seen.add(name)
        parts = name.split(".")
        stack += list(GRAPH.get(name, ())) + [".".join(parts[:i]) for i in range(1, len(parts))
                                                if ".".join(parts[:i]) in MODULES]
    return seen


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
