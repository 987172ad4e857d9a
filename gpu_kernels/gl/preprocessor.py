# SPDX-License-Identifier: GPL-3.0-or-later
"""GLSL preprocessing for gpu_kernels: ``#include``, ``#pragma once``, stage and variant defines.

Modelled on moderngl-window's program loader (one ``.glsl`` file holds several stages, each in an
``#if defined(VERTEX_SHADER)`` block) and Godot's shader variants (a variant is the same file
compiled with extra ``#define``s, e.g. ``MODE_SUN``).

Drivers number error lines in the *final* text, which after include expansion and define
injection matches no file on disk. ``#line`` would fix that in principle, but Mesa's llvmpipe
reads the source-string number of ``#line N S`` oddly, so instead every output line is recorded
in ``ShaderSource.line_map`` and ``format_compile_error`` maps driver logs back to ``path:line``.

Pure stdlib (no bpy, no moderngl) so it can be tested and used anywhere.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

SHADER_DIR = Path(__file__).parent.parent / "shaders"
DEFAULT_VERSION = "#version 430 core"
GENERATED = "<generated>"  # line_map file name of lines the preprocessor wrote itself
STAGES = {"vertex": "VERTEX_SHADER", "fragment": "FRAGMENT_SHADER",
          "geometry": "GEOMETRY_SHADER", "compute": "COMPUTE_SHADER"}

_INCLUDE = re.compile(r"^\s*#\s*include\b(.*)$")
_INCLUDE_ARG = re.compile(r'^\s*"([^"]+)"\s*(//.*)?$')
_PRAGMA_ONCE = re.compile(r"^\s*#\s*pragma\s+once\b")
_VERSION = re.compile(r"^\s*#\s*version\b")
_IF = re.compile(r"^\s*#\s*if(n?def)?\b")
_ENDIF = re.compile(r"^\s*#\s*endif\b")
_DIRECTIVE_STAGES = re.compile(r"^\s*#\s*(?:if|ifdef|ifndef|elif)\b.*$", re.M)
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
# Driver log lines. The leading number is the source-string index, always 0 for us (moderngl
# hands over one string per stage). Mesa's column is dropped: `path:line:` is what editors and
# people read, and the line is the part include expansion changes.
_LOG_FORMATS = (
    re.compile(r"^\d+:(?P<line>\d+)\(\d+\):\s*(?P<msg>.*)$"),  # Mesa:   0:12(5): error: ...
    re.compile(r"^\d+\((?P<line>\d+)\)\s*:\s*(?P<msg>.*)$"),   # NVIDIA: 0(12) : error C0000: ...
    re.compile(r"^(?P<kind>ERROR|WARNING):\s*\d+:(?P<line>\d+):\s*(?P<msg>.*)$"),  # AMD, Intel
)


class ShaderIncludeError(ValueError):
    """An ``#include`` that cannot be honoured: missing, malformed, cyclic, too deep, or a
    conflicting ``#version``. The message starts with the offending ``file:line``."""


class ShaderCompileError(RuntimeError):
    """A shader the driver rejected. Raise it with a log already run through
    ``format_compile_error``; it lives here so callers can catch it without importing moderngl."""


@dataclass(frozen=True)
class ShaderSource:
    """Final GLSL and where each of its lines came from.

    ``line_map[i]`` is ``(file_path_str, line_number)`` of output line ``i + 1``; lines the
    preprocessor wrote (version, defines, include guards) map to ``(GENERATED, output_line)``.
    """
    text: str
    line_map: list

    def origin(self, line: int) -> tuple[str, int] | None:
        """(file, line) of 1-based output ``line``, or None when out of range."""
        return self.line_map[line - 1] if 1 <= line <= len(self.line_map) else None


class _Expander:
    """One preprocess() call's state: output so far, #version seen, #pragma once bookkeeping."""

    def __init__(self, search_dirs: list[Path], max_depth: int):
        self.dirs, self.max_depth = search_dirs, max_depth
        self.out: list[tuple[str, str, int]] = []
        self.version: tuple[str, str, int] | None = None
        self.cond_depth = 0  # #if nesting at the current output position
        self.unconditional: set[Path] = set()  # once-files already emitted outside any #if
        self.guards: dict[Path, str] = {}
        self.cache: dict[Path, list[str]] = {}

    def emit(self, text: str, file: str, line: int) -> None:
        if _IF.match(text):
            self.cond_depth += 1
        elif _ENDIF.match(text):
            self.cond_depth -= 1
        self.out.append((text, file, line))

    def expand(self, path: Path, chain: list[Path], site: str) -> None:
        if path in chain:
            raise ShaderIncludeError(f"{site}: #include cycle: " + " -> ".join(map(str, chain + [path])))
        if len(chain) > self.max_depth:
            raise ShaderIncludeError(f"{site}: #include depth exceeds max_depth={self.max_depth}: "
                                     + " -> ".join(map(str, chain + [path])))
        if path not in self.cache:
            self.cache[path] = path.read_text(encoding="utf-8").splitlines()
        lines = self.cache[path]
        guard = None
        if chain and any(_PRAGMA_ONCE.match(l) for l in lines):
            if path in self.unconditional:
                return
            # We do not evaluate #if, so a once-file first seen inside e.g. the VERTEX_SHADER
            # block must not vanish from the FRAGMENT_SHADER block: there we emit it again under
            # a macro guard and let the GLSL preprocessor (which does know the branch) decide.
            if self.cond_depth > 0 or path in self.guards:
                guard = self.guards.setdefault(path, f"BOUNCE_ONCE_{len(self.guards)}")
                self.emit(f"#ifndef {guard}", GENERATED, 0)
                self.emit(f"#define {guard}", GENERATED, 0)
            if self.cond_depth <= (1 if guard else 0):
                self.unconditional.add(path)
        for n, line in enumerate(lines, 1):
            if _PRAGMA_ONCE.match(line):
                continue
            if _VERSION.match(line):
                self.take_version(line.strip(), path, n)
                continue
            m = _INCLUDE.match(line)
            if m:
                arg = _INCLUDE_ARG.match(m.group(1))
                if not arg:
                    raise ShaderIncludeError(f'{path}:{n}: malformed #include, expected #include "file.glsl"')
                self.expand(self.resolve(arg.group(1), path, n), chain + [path], f"{path}:{n}")
                continue
            self.emit(line, str(path), n)
        if guard:
            self.emit("#endif", GENERATED, 0)

    def take_version(self, text: str, path: Path, n: int) -> None:
        # GLSL allows exactly one #version, first in the text; hoist the first one we meet.
        if self.version is None:
            self.version = (text, str(path), n)
        elif text.split() != self.version[0].split():
            raise ShaderIncludeError(f"{path}:{n}: {text!r} conflicts with {self.version[0]!r} "
                                     f"from {self.version[1]}:{self.version[2]}")

    def resolve(self, rel: str, including: Path, n: int) -> Path:
        dirs = [including.parent, *self.dirs]
        for d in dirs:
            if (d / rel).is_file():
                return (d / rel).resolve()
        raise ShaderIncludeError(f'{including}:{n}: cannot find #include "{rel}" '
                                 f"(looked in {', '.join(map(str, dirs))})")


def _define_line(name: str, value) -> str:
    if not isinstance(name, str) or not _IDENT.match(name):
        raise ValueError(f"invalid #define name {name!r}")
    if value is None:
        return f"#define {name}"
    # bool first (it is an int): 1/0 so both `#if NAME` and `#ifdef NAME` work.
    text = ("1" if value else "0") if isinstance(value, bool) else str(value)
    if "\n" in text or "\r" in text:
        raise ValueError(f"#define {name}: value must be one line, got {text!r}")
    return f"#define {name} {text}"


def _stage_macro(stage: str) -> str:
    key = stage.lower()
    if key in STAGES:
        return STAGES[key]
    if stage.upper() in STAGES.values():
        return stage.upper()
    raise ValueError(f"unknown shader stage {stage!r}; expected one of {', '.join(STAGES)}")


def preprocess(name_or_path, defines: dict | None = None, stage: str | None = None,
               search_dirs=None, max_depth: int = 8) -> ShaderSource:
    """Expand ``name_or_path`` into one GLSL source for one stage/variant.

    Output: the file's own ``#version`` (else ``#version 430 core``), one ``#define`` per entry
    of ``defines`` in dict order (None: bare ``#define NAME``; bools: 1/0), ``#define
    <STAGE>_SHADER`` when ``stage`` is given ("vertex", "fragment", "geometry", "compute"), then
    the file with ``#include "x.glsl"`` replaced recursively. Includes resolve relative to the
    including file, then ``search_dirs``; a relative ``name_or_path`` is looked up in
    ``search_dirs``, then the working directory. Conditionals are not evaluated, so every stage
    of a file gets the same ``line_map``.
    """
    dirs = [Path(d) for d in (search_dirs or ())]
    path = Path(name_or_path)
    candidates = [path] if path.is_absolute() else [*(d / path for d in dirs), path]
    top = next((c.resolve() for c in candidates if c.is_file()), None)
    if top is None:
        raise FileNotFoundError(f"shader {str(path)!r} not found (looked for {', '.join(map(str, candidates))})")
    exp = _Expander(dirs, max_depth)
    exp.expand(top, [], str(top))
    head = [exp.version or (DEFAULT_VERSION, GENERATED, 0)]
    head += [(_define_line(k, v), GENERATED, 0) for k, v in (defines or {}).items()]
    if stage is not None:
        head.append((f"#define {_stage_macro(stage)}", GENERATED, 0))
    rows = head + exp.out
    line_map = [(GENERATED, i) if f == GENERATED else (f, n) for i, (_, f, n) in enumerate(rows, 1)]
    return ShaderSource("\n".join(t for t, _, _ in rows) + "\n", line_map)


def load(name, defines: dict | None = None, stage: str | None = None) -> ShaderSource:
    """``preprocess`` a shader from ``gpu_kernels/shaders/``, which also serves as include root."""
    return preprocess(name, defines, stage, search_dirs=[SHADER_DIR])


def load_program(name, defines: dict | None = None) -> dict[str, ShaderSource]:
    """One ShaderSource per stage a multi-stage file tests for, keyed like moderngl's
    ``ctx.program`` / ``ctx.compute_shader`` arguments ("vertex_shader", ...)."""
    plain = load(name, defines)
    found = {m for d in _DIRECTIVE_STAGES.findall(plain.text)
             for m in re.findall(r"\b(?:VERTEX|FRAGMENT|GEOMETRY|COMPUTE)_SHADER\b", d)}
    stages = [s for s, macro in STAGES.items() if macro in found]
    if not stages:
        raise ValueError(f"{name}: no #if defined(<STAGE>_SHADER) blocks; use load(name, stage=...)")
    return {f"{s}_shader": load(name, defines, s) for s in stages}


def format_compile_error(log: str, source: ShaderSource) -> str:
    """Rewrite driver log lines (Mesa ``0:12(5): ...``, NVIDIA ``0(12) : ...``, AMD/Intel
    ``ERROR: 0:12: ...``) as ``path:line: message`` through ``source.line_map``; other lines, and
    line numbers outside the source, pass through unchanged."""
    out = []
    src_lines = source.text.splitlines()
    for raw in log.splitlines():
        m = next((m for rx in _LOG_FORMATS if (m := rx.match(raw.strip()))), None)
        where = source.origin(int(m["line"])) if m else None
        if where is None:
            out.append(raw)
            continue
        kind = m.groupdict().get("kind")
        msg = f"{kind}: {m['msg']}" if kind else m["msg"]
        if where[0] == GENERATED:  # a bad define value: show the line, it exists in no file
            msg += f"  [in {src_lines[where[1] - 1].strip()!r}]"
        out.append(f"{where[0]}:{where[1]}: {msg}")
    return "\n".join(out)
