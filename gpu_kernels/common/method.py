# SPDX-License-Identifier: GPL-3.0-or-later
"""What a GI method's passes hand back to the pipeline (pipeline.METHOD_PASSES)."""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class MethodOutput:
    """`indirect`: RGBA32F texture, rgb = Diffuse Indirect (irradiance/π), a = voxel AO where `has_ao`;
    `glossy`: RGBA32F texture of Glossy Indirect or None; `key`: the cache key of the last pass (compose re-runs
    when it changes); `info`: the method's statistics (RenderResult.info)."""
    indirect: object
    glossy: object
    key: tuple
    info: dict = field(default_factory=dict)
    has_ao: bool = False
