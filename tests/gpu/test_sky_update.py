# SPDX-License-Identifier: GPL-3.0-or-later
"""The sky's visibility after an object's move (direct/sky.py SkyUpdate): a pixel whose tests (the four texels of
each direction, the edge cells' cones up to direct/eval.glsl sky_reach beyond them) can read a texel the move
redrew, or that the moved object can cover, is made anew; every other keeps its shares of one update ago. Against
a cold render of the moved scene: the same Diffuse and Glossy Direct to float32 rounding (1e-5 of the image's
mean: a pixel kept that should have been made anew is off by a whole direction's share, 1/64 here)."""
from dataclasses import replace

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common.lights import ShadowSettings
from bounce_gi.gpu_kernels.direct import sky
from bounce_gi.gpu_kernels.scene import Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from support.synthetic import box_quads, quad, quad_scene

SETTINGS = RenderSettings(method="lpv", width=96, height=72, shadow=ShadowSettings(
    cube_resolution=128, sky_directions=64, sky_resolution=64))


def _yard(x):
    """A floor, two walls and a box at `x`, lit by a blue sky alone."""
    floor = quad([(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], (0, 0, 1))
    wall = quad([(-4, 4, 0), (4, 4, 0), (4, 4, 3), (-4, 4, 3)], (0, -1, 0))
    side = quad([(-4, -4, 0), (-4, 4, 0), (-4, 4, 3), (-4, -4, 3)], (1, 0, 0))
    quads = [(floor, 0), (wall, 0), (side, 0)] + box_quads((x - 0.5, -0.5, 0.0), (x + 0.5, 0.5, 1.2), 1,
                                                            inward=False)
    return quad_scene(quads, [Material("floor", (0.6, 0.6, 0.6)), Material("box", (0.8, 0.3, 0.2))], [],
                      eye=(1.0, -7.0, 5.0), target=(0.0, 0.5, 0.5), world=(0.4, 0.5, 0.7))


@pytest.mark.parametrize("directions", (64, 50, 800), ids=("64 directions", "50: a last word of bits part-filled",
                                                             "800: more than the cones' bits hold, hard tests"))
def test_an_object_move_updates_the_skys_visibility_to_what_a_cold_render_gives(engines, monkeypatch, directions):
    warm, cold = engines
    updates, shares, tile_directions = [], [], sky.tile_directions

    def counted(ctx, programs, gbuffer, shadows, update):
        out = tile_directions(ctx, programs, gbuffer, shadows, update)
        bits = np.unpackbits(np.frombuffer(out.read(), np.uint32).view(np.uint8))
        shares.append(bits.mean() * 32 * (-(-len(update.table) // 32)) / len(update.table))
        updates.append(update)
        return out
    monkeypatch.setattr(sky, "tile_directions", counted)
    settings = replace(SETTINGS, shadow=replace(SETTINGS.shadow, sky_directions=directions))
    warm.render(_yard(0.0), settings)
    for x in (0.3, 0.6):
        result = warm.render(_yard(x), settings)
        fresh = cold.render(_yard(x), settings)
        cold.clear_cache()
        for name in ("Diffuse Direct", "Glossy Direct", "Combined"):
            a, b = result.passes[name], fresh.passes[name]
            assert np.abs(a - b).max() <= 1e-5 * np.abs(b).mean(), name
    print("share of (block, direction) pairs tested again:", shares)
    assert len(updates) == 2 and all(0.0 < s < 0.5 for s in shares)
