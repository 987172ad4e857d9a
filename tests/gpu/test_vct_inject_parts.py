# SPDX-License-Identifier: GPL-3.0-or-later
"""VCT's injection by parts (vct/parts.py): a scene lit by lamps, an emissive mesh and the sky injects each part
apart, per unit of its colour, and sums them. Checked: the sum is the injection of every light at once (the faces
within float rounding: the parts' sums differ from one pass's only in the order of the adds, which the injection's
compare-and-swap loops leave unordered anyway); an edit re-injects only the part it touched, or none where a part's
colour alone changed; and any edit gives what a render from scratch of the edited scene gives."""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct import parts
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from bounce_gi.gpu_kernels.vct.trace import read_level
from support.synthetic import box_quads, quad_scene

SETTINGS = RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32))
PARTS = tuple(f"vct_inject_{name}" for name in parts.PARTS)
PASSES = ("Diffuse Indirect", "Combined")
# Relative to the pass's largest value. A cold render and an edit sum the same parts in the same order; what may
# differ is the order of one part's compare-and-swap adds between two injections of it (float32: an ulp or so of a
# face's sum, carried through the bounces), measured 0 on llvmpipe in every case below; 1e-6 leaves room for that.
# The parts' sum against one injection of every light: measured 1.2e-7 (faces) and 1.7e-7 (Diffuse Indirect).
SAME = 1e-6


TWO = ((60.0, (-0.5, 0.2, 1.5)), (30.0, (0.6, -0.3, 1.2)))  # two lamps: (power, place)


def _room(lamps=((60.0, (-0.5, 0.2, 1.5)),), world=(0.05, 0.07, 0.1), emission=(4.0, 3.0, 2.0)):
    """An open-topped room (the sky comes in from above) with a block; `lamps`: (power, place) of point lights;
    the block's top is an emitter."""
    lights = []
    for i, (power, place) in enumerate(lamps):
        matrix = np.eye(4)
        matrix[:3, 3] = place
        lights.append(Light(f"lamp{i}", "POINT", (1.0, 0.9, 0.8), power, matrix))
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0, skip=((2, "hi"),))
    block = box_quads((-0.3, -0.3, 0.0), (0.3, 0.3, 0.7), 1, inward=False)
    quads += [(q, 2) if i == 5 else (q, m) for i, (q, m) in enumerate(block)]  # the block's top (+z) emits
    mats = [Material("walls", (0.7, 0.6, 0.5)), Material("block", (0.2, 0.5, 0.8)),
            Material("glow", (0.8, 0.8, 0.8), emission=emission)]
    return quad_scene(quads, mats, lights, (0.0, -0.9, 1.5), (0.0, 0.5, 0.3), world=world)


def _rerun(result) -> set:
    return {k for k in result.timings if k not in result.skipped and k != "total"}


def _same(a, b, tol=SAME):
    for name in PASSES:
        x, y = a.passes[name], b.passes[name]
        assert np.abs(x - y).max() <= tol * max(float(np.abs(y).max()), 1e-12), name


def _faces(engine) -> list:
    """vct_inject's six face volumes, as (voxels, 4) arrays."""
    pipe = engine.pipeline

    def grab(ctx):
        faces = pipe.cache.entries["vct_inject"].value
        return [read_level(ctx, pipe.programs, t, faces.grid, 0).reshape(-1, 4) for t in faces.textures]
    return engine.worker.call(grab)


def test_the_parts_sum_to_one_injection_of_every_light(monkeypatch):
    """Lamps, emitter and sky each injected apart and summed: the same faces as one injection of every light."""
    by_parts = Engine()
    r = by_parts.render(_room(), SETTINGS)
    assert set(PARTS) <= _rerun(r), r.timings
    summed = _faces(by_parts)
    monkeypatch.setattr(parts, "PART_BYTES_CAP", 0)
    at_once = Engine()
    one = at_once.render(_room(), SETTINGS)
    assert not set(PARTS) & set(one.timings)
    for a, b in zip(summed, _faces(at_once)):
        assert np.abs(a - b).max() <= SAME * np.abs(b).max()
        assert np.array_equal(a[:, 3], b[:, 3])  # the coverage is the geometry's
    _same(r, one)
    flux, flux_one = r.info["bounces"][0]["flux"], one.info["bounces"][0]["flux"]  # the tail's and epsilon's input
    assert np.allclose(flux, flux_one, rtol=SAME, atol=0.0), (flux, flux_one)


def test_each_part_is_lit_by_its_own_records(monkeypatch):
    """Each part's injection sees its lights alone: as many records in the buffer as its light count says."""
    from bounce_gi.gpu_kernels.common.lights import LIGHT_DTYPE
    from bounce_gi.gpu_kernels.vct import inject

    seen, injected = [], inject.inject

    def spy(ctx, programs, scene, geometry, textures, vox, shadows, *args):
        seen.append((shadows.light_count, shadows.light_ssbo.size // LIGHT_DTYPE.itemsize))
        return injected(ctx, programs, scene, geometry, textures, vox, shadows, *args)
    monkeypatch.setattr(inject, "inject", spy)
    Engine().render(_room(lamps=TWO), SETTINGS)
    assert len(seen) == 3 and all(count == records for count, records in seen), seen
    assert {count for count, _ in seen} >= {1, 2}, seen  # the sky; two lamps (and the emitter's clusters)


def test_switching_between_parts_and_one_injection(monkeypatch):
    """The same scene by parts, then (the cap lowered) all at once, then by parts again: the parts' passes dropped
    and made again, the images the same within float rounding."""
    engine = Engine()
    by_parts = engine.render(_room(), SETTINGS)
    monkeypatch.setattr(parts, "PART_BYTES_CAP", 0)
    at_once = engine.render(_room(), SETTINGS)
    assert not set(PARTS) & set(engine.pipeline.cache.entries) and "vct_inject" in _rerun(at_once)
    monkeypatch.undo()
    again = engine.render(_room(), SETTINGS)
    assert set(PARTS) <= _rerun(again)
    _same(at_once, by_parts)
    _same(again, by_parts)


@pytest.mark.parametrize("before,edit,kept", [
    ({}, {"lamps": ((140.0, (-0.5, 0.2, 1.5)),)}, PARTS),          # the only lamp's power: no part again
    ({}, {"world": (0.02, 0.09, 0.2)}, PARTS),                      # the sky's colour: no part again
    ({}, {"lamps": ((60.0, (0.4, 0.1, 1.4)),)}, PARTS[1:]),         # the lamp moved: the lamps again
    ({"lamps": TWO}, {"lamps": (TWO[0], (75.0, TWO[1][1]))}, PARTS[1:]),  # one of two lamps' power: the lamps again
], ids=["lamp power", "world colour", "lamp move", "one of two lamps"])
def test_an_edit_injects_only_the_part_it_touched(before, edit, kept):
    engine = Engine()
    engine.render(_room(**before), SETTINGS)
    edited = engine.render(_room(**{**before, **edit}), SETTINGS)
    rerun = _rerun(edited)
    assert not set(kept) & rerun, rerun
    assert set(PARTS) - set(kept) <= rerun and "vct_inject" in rerun, rerun
    _same(edited, Engine().render(_room(**{**before, **edit}), SETTINGS))


def test_a_scene_left_with_one_part_drops_the_others():
    """The world turned black and the emitter off: the lamps' part alone is summed (times the faces' albedo, into
    faces of the injection's own); the others' volumes released."""
    engine = Engine()
    engine.render(_room(), SETTINGS)
    cache = engine.pipeline.cache
    assert set(PARTS) <= set(cache.entries)
    dark = {"world": (0.0, 0.0, 0.0), "emission": (0.0, 0.0, 0.0)}
    one = engine.render(_room(**dark), SETTINGS)
    assert set(PARTS) & set(cache.entries) == {"vct_inject_lamps"} and "vct_inject" in _rerun(one)
    lamps, faces = cache.entries["vct_inject_lamps"].value, cache.entries["vct_inject"].value
    assert not set(faces.textures) & set(lamps.textures)
    _same(one, Engine().render(_room(**dark), SETTINGS))


def test_a_part_added_is_summed_with_the_others():
    """A lamp-lit scene whose world is switched on: the sky's part is made and summed with the lamps' (injected
    again too: the sky's maps moved the lamp's in the shadow atlas), as a render from scratch sums them."""
    engine = Engine()
    dark = {"world": (0.0, 0.0, 0.0), "emission": (0.0, 0.0, 0.0)}
    engine.render(_room(**dark), SETTINGS)
    lit = engine.render(_room(emission=(0.0, 0.0, 0.0)), SETTINGS)
    rerun = _rerun(lit)
    assert "vct_inject_sky" in rerun and "vct_inject" in rerun, rerun
    _same(lit, Engine().render(_room(emission=(0.0, 0.0, 0.0)), SETTINGS))


def test_parts_bytes():
    """Parts apart only where their volumes fit the cap (else one injection of every light, summed alike); the
    estimate from a scene counts them."""
    from bounce_gi.gpu_kernels.common.grid import Grid

    grid = Grid((0.0, 0.0, 0.0), 0.1, (64, 64, 64))
    assert parts.parts_bytes(grid, 1) == 64 ** 3 * 96 and parts.fits(grid, 1) and parts.fits(grid, 3)
    assert parts.fits(Grid((0.0, 0.0, 0.0), 0.1, (512, 512, 512)), 1)  # one part is every light
    assert parts.parts_bytes(grid, 3) == 3 * 64 ** 3 * 96 <= parts.PART_BYTES_CAP
    assert parts.parts_bytes(Grid((0.0, 0.0, 0.0), 0.1, (128, 128, 128)), 2) == 128 ** 3 * 96  # all lights at once
    assert parts.scene_parts(_room()) == 3
    assert parts.scene_parts(_room(world=(0.0, 0.0, 0.0), emission=(0.0, 0.0, 0.0))) == 1
