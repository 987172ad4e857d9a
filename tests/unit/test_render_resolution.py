# SPDX-License-Identifier: GPL-3.0-or-later
"""addon.extract.camera.render_resolution: the render size as Blender computes it, in integers (size · percentage
/ 100, rounded down), which is what the render engine's result is allocated at."""
from types import SimpleNamespace

from bounce_gi.addon.extract.camera import render_resolution


def test_render_size_is_integer_arithmetic_like_blenders():
    # 100 · 0.29 is 28.999… in floats: float scaling would give 28 where Blender allocates 29.
    assert render_resolution(SimpleNamespace(resolution_x=100, resolution_y=200, resolution_percentage=29)) == (29, 58)
    assert render_resolution(SimpleNamespace(resolution_x=1001, resolution_y=3, resolution_percentage=33)) == (330, 1)
    assert render_resolution(SimpleNamespace(resolution_x=1, resolution_y=1, resolution_percentage=1)) == (1, 1)
    assert render_resolution(None, resolution=(64.0, 48)) == (64, 48)
