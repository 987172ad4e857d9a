# SPDX-License-Identifier: GPL-3.0-or-later
"""What a render is asked for: the method, the resolution and each stage's settings; and the checks that turn bad
input into one clear message (SceneError) before any GPU work starts."""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

from .common.lights import ShadowSettings
from .lpv.settings import LpvSettings
from .scene import Scene
from .vct.settings import VctSettings

METHODS = ("none", "lpv", "vct")


class SceneError(ValueError):
    """The scene cannot be rendered as given (message is for the user)."""


@dataclass(frozen=True)
class RenderSettings:
    method: str = "none"
    width: int = 640
    height: int = 480
    shadow: ShadowSettings = field(default_factory=ShadowSettings)
    lpv: LpvSettings = field(default_factory=LpvSettings)
    vct: VctSettings = field(default_factory=VctSettings)

    def key(self) -> str:
        return repr(sorted(asdict(self).items()))


def check_method(settings: RenderSettings) -> None:
    if settings.method not in METHODS:
        raise SceneError(f"unknown method '{settings.method}' (choose from {', '.join(METHODS)})")


def check_renderable(scene: Scene, settings: RenderSettings) -> None:
    """A render from the scene camera: a known method, a camera, a sane resolution."""
    check_method(settings)
    if scene.camera is None:
        raise SceneError("the scene has no camera")
    if settings.width < 1 or settings.height < 1 or settings.width > 16384 or settings.height > 16384:
        raise SceneError(f"resolution {settings.width}x{settings.height} is out of range (1..16384)")
