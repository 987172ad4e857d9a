# SPDX-License-Identifier: GPL-3.0-or-later
"""Compile `.glsl` files into moderngl programs, once per (file, defines), with errors mapped to file:line."""
from __future__ import annotations

from . import preprocessor as spp


class ProgramCache:
    """Programs for one context. `raster(name, defines)` for vertex+fragment files, `compute(name, defines)`."""

    def __init__(self, ctx):
        self.ctx = ctx
        self._programs: dict = {}

    def _key(self, kind, name, defines):
        return kind, name, tuple(sorted((defines or {}).items()))

    def raster(self, name: str, defines: dict | None = None):
        key = self._key("raster", name, defines)
        if key not in self._programs:
            stages = spp.load_program(name, defines)
            try:
                self._programs[key] = self.ctx.program(**{k: v.text for k, v in stages.items()})
            except Exception as exc:  # moderngl raises a plain Error carrying the driver log
                first = next(iter(stages.values()))
                raise spp.ShaderCompileError(spp.format_compile_error(str(exc), first)) from None
        return self._programs[key]

    def compute(self, name: str, defines: dict | None = None):
        key = self._key("compute", name, defines)
        if key not in self._programs:
            source = spp.load(name, defines, stage="compute")
            try:
                self._programs[key] = self.ctx.compute_shader(source.text)
            except Exception as exc:
                raise spp.ShaderCompileError(spp.format_compile_error(str(exc), source)) from None
        return self._programs[key]

    def release(self) -> None:
        for program in self._programs.values():
            program.release()
        self._programs.clear()
