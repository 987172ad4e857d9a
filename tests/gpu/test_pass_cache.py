# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.pass_cache: skip what did not change, release what is replaced; and the real pipeline re-running
exactly the passes downstream of a change (docs/architecture.md, The pipeline and its pass cache), with the direct light checked against the analytic value."""
import math
import time

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common.lights import ShadowSettings
from bounce_gi.gpu_kernels.gl.pass_cache import PassCache
from bounce_gi.gpu_kernels.scene import Camera, Light, Material, Scene


class Resource:
    """Stands in for a GL object: counts release() calls."""

    def __init__(self, tag):
        self.tag = tag
        self.released = 0

    def release(self):
        self.released += 1


class Counter:
    def __init__(self):
        self.calls = {}

    def fn(self, name, value):
        def run():
            self.calls[name] = self.calls.get(name, 0) + 1
            return value
        return run


# --------------------------------------------------------------------------- PassCache with fakes

def test_same_key_skips_and_returns_cached_value():
    cache, c = PassCache(), Counter()
    first = Resource("a")
    cache.begin_frame()
    assert cache.run("a", ("k",), c.fn("a", first)) is first
    assert cache.skipped == [] and cache.timings["a"] >= 0.0
    cache.begin_frame()
    again = cache.run("a", ("k",), c.fn("a", Resource("never")))
    assert again is first and c.calls["a"] == 1
    assert cache.timings == {"a": 0.0} and cache.skipped == ["a"]
    assert first.released == 0


def test_changed_key_reruns_and_releases_old_value():
    cache, c = PassCache(), Counter()
    old = {"tex": Resource("t"), "list": [Resource("l1"), (Resource("l2"),)], "plain": 3}
    cache.run("a", (1,), c.fn("a", old))
    new = Resource("new")
    cache.begin_frame()
    assert cache.run("a", (2,), c.fn("a", new)) is new
    assert c.calls["a"] == 2 and cache.skipped == []
    # Nested resources in the old output were each released exactly once; the new one is alive.
    assert (old["tex"].released, old["list"][0].released, old["list"][1][0].released) == (1, 1, 1)
    assert new.released == 0
    # Re-running to the very same object (a pass that returns a persistent resource) must not release it.
    cache.run("a", (3,), c.fn("a", new))
    assert new.released == 0
    cache.clear()
    assert new.released == 1 and cache.entries == {}


def test_drop_releases_every_output_of_a_pass_and_nothing_else():
    cache, c = PassCache(keep={"a": 2}), Counter()
    first, second, other = Resource("1"), Resource("2"), Resource("b")
    cache.run("a", (1,), c.fn("a", first))
    cache.run("a", (2,), c.fn("a", second))
    cache.run("b", (1,), c.fn("b", other))
    cache.drop(["a", "never run"])
    assert (first.released, second.released, other.released) == (1, 1, 0)
    assert "a" not in cache.entries and not cache.older.get("a") and cache.kept("b")
    cache.run("a", (1,), c.fn("a", Resource("again")))
    assert c.calls["a"] == 3  # made again: nothing of it was kept


def test_timing_measures_the_pass_and_waits_for_finish():
    finished = []
    cache = PassCache(finish=lambda: (time.sleep(0.02), finished.append(1)))
    cache.begin_frame()
    cache.run("slow", (1,), lambda: time.sleep(0.03))
    assert finished == [1]
    assert cache.timings["slow"] >= 0.045  # the pass plus the GPU wait, not just the Python call
    cache.begin_frame()
    cache.run("slow", (1,), lambda: time.sleep(0.03))
    assert finished == [1] and cache.timings == {"slow": 0.0}  # a skipped pass does not wait for the GPU


def _graph(cache, counter, inputs):
    """a ← x; b ← a, y; c ← b. Keys of downstream passes contain the keys of what they consume."""
    ka = (inputs["x"],)
    cache.run("a", ka, counter.fn("a", Resource("a")))
    kb = (ka, inputs["y"])
    cache.run("b", kb, counter.fn("b", Resource("b")))
    kc = (kb,)
    cache.run("c", kc, counter.fn("c", Resource("c")))


def test_downstream_keys_rerun_transitively():
    cache, c = PassCache(), Counter()
    inputs = {"x": "x0", "y": "y0"}
    _graph(cache, c, inputs)
    assert c.calls == {"a": 1, "b": 1, "c": 1}
    cache.begin_frame()
    _graph(cache, c, inputs)
    assert c.calls == {"a": 1, "b": 1, "c": 1} and cache.skipped == ["a", "b", "c"]
    cache.begin_frame()
    _graph(cache, c, {**inputs, "y": "y1"})  # only b's own input: a skipped, b and c re-run
    assert c.calls == {"a": 1, "b": 2, "c": 2} and cache.skipped == ["a"]
    cache.begin_frame()
    _graph(cache, c, {"x": "x1", "y": "y1"})  # a's input: everything downstream re-runs
    assert c.calls == {"a": 2, "b": 3, "c": 3} and cache.skipped == []


# --------------------------------------------------------------------------- the real pipeline

SUN_STRENGTH = 3.0
FLOOR_ALBEDO = (0.5, 0.4, 0.3)
BOX = (np.array([-0.5, -0.5, 0.0]), np.array([0.5, 0.5, 1.0]))
ALL_PASSES = {"geometry", "textures", "emitter_shells", "shadow_depth", "shadow_maps", "gbuffer", "sky_visibility",
              "direct_light", "compose"}


def _quad(a, b, c, d, normal):
    pos = np.array([[a, b, c], [a, c, d]], np.float64)
    nrm = np.broadcast_to(np.asarray(normal, np.float64), (2, 3, 3))
    return pos, nrm


def _box_triangles(lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    faces = [
        (((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)), (0, 0, 1)),
        (((x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)), (0, 0, -1)),
        (((x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)), (1, 0, 0)),
        (((x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)), (-1, 0, 0)),
        (((x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)), (0, 1, 0)),
        (((x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)), (0, -1, 0)),
    ]
    return [_quad(*corners, n) for corners, n in faces]


def _rotation_x(angle):
    c, s = math.cos(angle), math.sin(angle)
    m = np.eye(4)
    m[1:3, 1:3] = [[c, -s], [s, c]]
    return m


def sun(tilt_deg, location=(0, 0, 5)):
    """A sun tilted `tilt_deg` from straight down (about X): the floor's cosθ is cos(tilt)."""
    m = _rotation_x(math.radians(tilt_deg))
    m[:3, 3] = location
    return Light("sun", "SUN", (1.0, 1.0, 1.0), SUN_STRENGTH, m)


def camera(eye, target=(0, 0, 0)):
    """Camera-to-world matrix looking from eye to target (+Y up-ish), built by hand."""
    eye, target = np.asarray(eye, np.float64), np.asarray(target, np.float64)
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross([0, 0, 1.0], back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, up, back, eye
    return Camera(matrix_world=m, lens=30.0, clip_start=0.1, clip_end=100.0)


def make_scene(light, cam):
    quads = [_quad((-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0), (0, 0, 1))] + _box_triangles(*BOX)
    pos = np.concatenate([q[0] for q in quads]).astype(np.float32)
    nrm = np.concatenate([q[1] for q in quads]).astype(np.float32)
    mat = np.array([0, 0] + [1] * 12, np.int32)
    return Scene(pos, nrm, np.zeros((len(pos), 3, 2), np.float32), mat,
                 [Material("floor", FLOOR_ALBEDO), Material("box", (0.8, 0.3, 0.2))],
                 lights=[light], camera=cam, resolution=(160, 120))


@pytest.fixture(scope="module")
def engine():
    from bounce_gi.gpu_kernels.engine import Engine
    from bounce_gi.gpu_kernels.gl.context import GpuUnavailableError

    eng = Engine()
    try:
        eng.gl_info()
    except GpuUnavailableError as exc:
        eng.worker.shutdown()
        pytest.skip(str(exc))
    yield eng
    if eng.pipeline is not None:
        eng.worker.call(lambda ctx: eng.pipeline.release())
    eng.worker.shutdown()


@pytest.fixture(scope="module")
def settings():
    from bounce_gi.gpu_kernels.settings import RenderSettings

    return RenderSettings(method="none", width=160, height=120,
                          shadow=ShadowSettings(sun_resolution=512, spot_resolution=256, cube_resolution=128,
                                                area_cube_resolution=64, sample_cube_resolution=64))


def _ray_hits_box(p, d, lo, hi):
    """Slab test: does the ray p + t·d (t > 0) hit the axis-aligned box [lo, hi]?"""
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (lo - p) / d
        t1 = (hi - p) / d
    tmin = np.nanmax(np.minimum(t0, t1), axis=-1)
    tmax = np.nanmin(np.maximum(t0, t1), axis=-1)
    return (tmax >= np.maximum(tmin, 0.0))


def lit_floor_mask(passes, light, margin=0.25):
    """Floor pixels whose path to the sun misses the box by at least `margin` (clear of PCF penumbrae)."""
    pos = passes["Position"].reshape(-1, 3).astype(np.float64)
    nrm = passes["Normal"].reshape(-1, 3)
    floor = (np.abs(pos[:, 2]) < 1e-4) & (nrm[:, 2] > 0.999) & (np.abs(pos[:, :2]).max(axis=1) < 4.9)
    lo, hi = BOX
    blocked = _ray_hits_box(pos, np.broadcast_to(-light.direction, pos.shape), lo - margin, hi + margin)
    return (floor & ~blocked).reshape(passes["Position"].shape[:2])


def check_direct(passes, light, tilt_deg):
    mask = lit_floor_mask(passes, light)
    assert mask.sum() > 2000, "too few lit floor pixels to check"
    expected = SUN_STRENGTH * math.cos(math.radians(tilt_deg)) / math.pi
    got = passes["Diffuse Direct"][mask]
    np.testing.assert_allclose(got, expected, rtol=1e-4)
    np.testing.assert_allclose(passes["Diffuse Color"][mask], np.broadcast_to(FLOOR_ALBEDO, got.shape), rtol=1e-6)
    # And the box's shadow really is there: floor pixels whose sun ray passes through the box (well inside).
    pos = passes["Position"].reshape(-1, 3).astype(np.float64)
    floor = (np.abs(pos[:, 2]) < 1e-4) & (passes["Normal"].reshape(-1, 3)[:, 2] > 0.999)
    lo, hi = BOX
    umbra = floor & _ray_hits_box(pos, np.broadcast_to(-light.direction, pos.shape), lo + 0.2, hi - 0.2)
    assert umbra.sum() > 20
    assert passes["Diffuse Direct"].reshape(-1, 3)[umbra].max() < 1e-3 * expected


def test_pipeline_reruns_only_what_changed(engine, settings):
    cam1 = camera((0.0, -7.0, 6.0))
    scene = make_scene(sun(-30.0), cam1)
    first = engine.render(scene, settings)
    assert set(first.skipped) == set()  # a fresh engine runs everything
    assert ALL_PASSES <= set(first.timings)
    check_direct(first.passes, scene.lights[0], -30.0)

    # Same scene (rebuilt, equal content): every pass skipped, timings 0, the same passes (the depth atlas: unasked).
    second = engine.render(make_scene(sun(-30.0), cam1), settings)
    assert set(second.skipped) == ALL_PASSES - {"shadow_depth"}
    assert all(second.timings[p] == 0.0 for p in ALL_PASSES - {"shadow_depth"})
    for name, image in first.passes.items():
        np.testing.assert_array_equal(second.passes[name], image)

    # Move only the light: shadows and lighting re-run; geometry, textures, G-buffer, sky (there is none) do not.
    moved = make_scene(sun(-50.0), cam1)
    third = engine.render(moved, settings)
    assert set(third.skipped) == {"geometry", "textures", "emitter_shells", "light_sources", "gbuffer",
                                  "sky_visibility"}
    assert {"shadow_depth", "shadow_maps", "direct_light", "compose"}.isdisjoint(third.skipped)
    check_direct(third.passes, moved.lights[0], -50.0)
    np.testing.assert_array_equal(third.passes["Position"], first.passes["Position"])

    # Change only the camera: G-buffer, lighting and compose re-run; geometry, textures, shadow maps do not.
    turned = make_scene(sun(-50.0), cam2 := camera((3.0, -6.0, 7.0)))
    fourth = engine.render(turned, settings)
    assert set(fourth.skipped) == {"geometry", "textures", "emitter_shells", "shadow_maps"}
    assert not np.array_equal(fourth.passes["Position"], third.passes["Position"])
    check_direct(fourth.passes, turned.lights[0], -50.0)

    # Change only the world colour: the world is a light (common/lights.py: the sky light), so the light passes
    # re-run — shadow maps, direct light, compose — and geometry, textures, G-buffer do not.
    world = make_scene(sun(-50.0), cam2)
    world.world.color = (0.1, 0.2, 0.3)
    fifth = engine.render(world, settings)
    assert set(fifth.skipped) == {"geometry", "textures", "emitter_shells", "light_sources", "gbuffer"}

    # Another world colour, and then a brighter sun: the lights' records change, no shadow view does, so the
    # depth atlas (the sky's 576 maps among them) and the sky's visible shares are kept — and the image is what a
    # cold render gives.
    kept = {"geometry", "textures", "emitter_shells", "light_sources", "shadow_depth", "gbuffer", "sky_visibility"}
    recoloured = make_scene(sun(-50.0), cam2)
    recoloured.world.color = (0.3, 0.2, 0.1)
    sixth = engine.render(recoloured, settings)
    assert set(sixth.skipped) == kept
    brighter = make_scene(sun(-50.0), cam2)
    brighter.world.color, brighter.lights[0].power = (0.3, 0.2, 0.1), 2.0 * brighter.lights[0].power
    seventh = engine.render(brighter, settings)
    assert set(seventh.skipped) == kept
    from bounce_gi.gpu_kernels.engine import Engine

    cold_engine = Engine()
    try:
        for scene_, warm in ((recoloured, sixth), (brighter, seventh)):
            cold = cold_engine.render(scene_, settings)
            for name in ("Diffuse Direct", "Combined"):
                np.testing.assert_array_equal(warm.passes[name], cold.passes[name])
    finally:
        cold_engine.shutdown()


def test_a_pass_keeps_as_many_outputs_as_asked_and_releases_the_rest():
    """keep = 2: alternating two keys (the viewport's draft and final settings) re-runs neither after the first
    time; a third key evicts the least recently used one, which is released exactly once."""
    cache, c = PassCache(keep={"t": 2}), Counter()
    a, b, third = Resource("a"), Resource("b"), Resource("c")
    for key, value in (("A", a), ("B", b), ("A", None), ("B", None), ("A", None)):
        cache.begin_frame()
        got = cache.run("t", (key,), c.fn("t", value))
        assert got is {"A": a, "B": b}[key]
    assert c.calls["t"] == 2 and cache.skipped == ["t"]
    cache.run("t", ("C",), c.fn("t", third))  # A is newest, B the older one: B goes
    assert b.released == 1 and a.released == 0 and third.released == 0
    cache.clear()
    assert a.released == 1 and third.released == 1 and b.released == 1
