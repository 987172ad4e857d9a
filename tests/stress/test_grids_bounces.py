# SPDX-License-Identifier: GPL-3.0-or-later
"""Grid sizes, bounce and iteration counts at their extremes: energy stays bounded (support/stress.check_sane's
analytic bound), and a grid too large for the memory there is gives one clear message before any allocation."""
from dataclasses import replace

import numpy as np
import pytest

from bounce_gi.gpu_kernels import settings as render_settings
from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.settings import SceneError
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.stress import box_room, check_sane, full_only, settings


def render(engine, scene, method, **kw):
    s = settings(method, **kw)
    result = engine.render(scene, s)
    check_sane(result, scene, s)
    return result


@pytest.mark.parametrize("resolution", (4, 8, 12, 16, *full_only(24, 32, 64)))
def test_lpv_grid_sizes(engine, resolution):
    render(engine, box_room(), "lpv", resolution=resolution)


# 256³ (--stress-full): 140 s and about 9 GiB on the 2-core llvmpipe machine (2026-12-05); the LPV's 256³ would need
# 36 GiB there, which test_a_grid_too_large_for_the_memory_is_one_clear_message covers.
@pytest.mark.parametrize("resolution", (16, 24, 32, *full_only(64, 128, 256)))
def test_vct_grid_sizes(engine, resolution):
    render(engine, box_room(), "vct", resolution=resolution)


@pytest.mark.parametrize("method, resolution", [("lpv", 3), ("lpv", 257), ("vct", 8), ("vct", 1024)])
def test_a_grid_out_of_range_is_one_clear_message(method, resolution):
    with pytest.raises(ValueError, match=f"resolution {resolution} out of range"):
        settings(method, resolution=resolution)


@pytest.mark.parametrize("method, resolution", [("lpv", 128), ("vct", 256)])
def test_a_grid_too_large_for_the_memory_is_one_clear_message(engine, monkeypatch, method, resolution):
    """With 2 GiB available, a 128³ LPV (about 4.7 GiB) or a 256³ VCT (about 15 GiB) is refused before any
    allocation; once the memory is there the next render works."""
    monkeypatch.setattr(render_settings, "available_memory", lambda: 2 * 2 ** 30)
    with pytest.raises(SceneError, match=r"needs about [\d.]+ GiB of memory, more than the 2.0 GiB available"):
        engine.render(box_room(), settings(method, resolution=resolution))
    monkeypatch.undo()
    render(engine, box_room(), method)


@pytest.mark.parametrize("method, resolution, sky", [("vct", 16, False), ("vct", 32, False), ("vct", 32, True),
                                                    ("lpv", 12, False), ("lpv", 16, False)])
def test_the_memory_estimate_covers_what_a_render_allocates(engine, monkeypatch, method, resolution, sky):
    """settings.method_bytes against the peak of the 3D textures and buffers a render holds at once (each counted
    from its creation to its release): at least all of it (the check must not let through what does not fit), at
    most 1.6× plus the fixed part (the VPL buffers, sized by the RSMs and clusters rather than the grid: up to twice
    the peak at 12³, where they are most of it). The peak, not the sum of every allocation: the LPV voxelises its
    receivers once per axis, releasing each voxelisation's textures before the next (lpv/receivers.py). With a sky
    too, VCT injects the lamp and the sky apart and keeps both parts' faces (vct/parts.py)."""
    import moderngl

    live, peak = {}, [0]
    texture3d, buffer = moderngl.Context.texture3d, moderngl.Context.buffer
    sizes = {"f1": 1, "u1": 1, "i1": 1, "f2": 2, "u2": 2, "i2": 2}

    def held(obj, nbytes):
        live[id(obj)] = nbytes
        peak[0] = max(peak[0], sum(live.values()))
        return obj

    def counted_texture3d(self, size, components, data=None, **kw):
        nbytes = int(np.prod(size)) * components * sizes.get(kw.get("dtype", "f1"), 4)
        return held(texture3d(self, size, components, data, **kw), nbytes)

    def counted_buffer(self, data=None, *, reserve=0, **kw):
        return held(buffer(self, data, reserve=reserve, **kw), reserve or (len(data) if data is not None else 0))

    def released(cls):
        release = cls.release

        def counted_release(self):
            live.pop(id(self), None)
            return release(self)
        return counted_release

    monkeypatch.setattr(moderngl.Context, "texture3d", counted_texture3d)
    monkeypatch.setattr(moderngl.Context, "buffer", counted_buffer)
    for cls in (moderngl.Texture3D, moderngl.Buffer):
        monkeypatch.setattr(cls, "release", released(cls))
    scene = box_room(1.0 + resolution * 1e-3 + 1e-4 * sky)  # a scene of its own, so every pass runs and allocates
    if sky:
        scene.world = replace(scene.world, color=(0.3, 0.3, 0.3))
    s = settings(method, resolution=resolution)
    engine.render(scene, s)
    monkeypatch.undo()
    estimate = render_settings.method_bytes(scene, s)
    print(f"{method} {resolution}³: estimate {estimate / 2 ** 20:.1f} MiB, peak held {peak[0] / 2 ** 20:.1f} MiB")
    fixed = {"lpv": render_settings.LPV_FIXED_BYTES, "vct": render_settings.VCT_FIXED_BYTES}[method]
    assert peak[0] <= estimate <= 1.6 * peak[0] + fixed


@pytest.mark.parametrize("method, kw", [
    ("lpv", {"bounces": 50}),
    ("lpv", {"bounces": 50, "gathered_bounces": 0}),
    ("lpv", {"bounces": 50, "transport": "propagate", "max_iterations": 16}),
    ("vct", {"bounces": 16, "gathered_bounces": 0}),
    ("vct", {"bounces": 16})], ids=("lpv gather 50", "lpv gather all 50", "lpv propagate 50", "vct gather all 16",
                                    "vct 16 with tail"))
def test_many_bounces_stay_bounded(engine, method, kw):
    render(engine, box_room(), method, **kw)


@pytest.mark.parametrize("albedo", (0.99, 1.0))
def test_fifty_bounces_of_albedo_one_stay_finite(engine, albedo):
    """White walls: every bounce adds about as much as the last; 50 bounces stay finite and below 50 × D."""
    render(engine, box_room(albedo=albedo, block_albedo=(albedo,) * 3), "lpv", bounces=50)


def test_vct_refuses_more_than_sixteen_bounces():
    with pytest.raises(ValueError, match="bounces 50 out of range 1..16"):
        settings("vct", bounces=50)


@pytest.mark.parametrize("iterations", (1, 1000))
def test_propagation_iterations_stay_bounded(engine, iterations):
    """1 or 1000 propagation steps with the stop test off (epsilon 0): light leaves through the grid's open borders
    or is absorbed, never created."""
    result = render(engine, box_room(), "lpv", transport="propagate", bounces=1, max_iterations=iterations,
                    epsilon=0.0)
    assert result.info["cascades"][0]["iterations"] == iterations


def test_lpv_epsilon_zero_settings_are_accepted():
    assert LpvSettings(epsilon=0.0).epsilon == 0.0 and VctSettings().bounces == 8
