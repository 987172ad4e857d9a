# SPDX-License-Identifier: GPL-3.0-or-later
"""A material's colour edit redoes only what its colour enters: no shadow map, RSM view (lpv/rsm.glsl holds no
colour) nor — for a dielectric — Diffuse or Glossy Direct (scene.material_keys "shading"); the LPV's first bounce
adds the edit's change to the kept one (lpv/passes.recolor): a dielectric's as its colour's change times its texels'
first bounce per unit colour, binned once and reused by its next edit, a metal's binned as it is.

Against a cold render of the edited scene: the direct passes are equal, the indirect ones differ by the rounding of
the float32 records that are summed in another order (the kept sum plus the change, against the sum at the new
colours): measured max |Δ| 2.4e-7 of images whose largest value is ~1 on the example scenes. Bound 1e-5 of the
image's largest value: a change binned into the wrong clusters or lights, or a basis reused after it went stale,
moves the edited material's bounce by 1e-2 or more."""
import numpy as np

from bounce_gi.gpu_kernels.common.lights import ShadowSettings
from bounce_gi.gpu_kernels.lpv import gather
from bounce_gi.gpu_kernels.scene import Light, Material
from support.synthetic import box_quads, quad, quad_scene

BOUND = 1e-5
BASE = [Material("floor", (0.6, 0.6, 0.6)), Material("box", (0.8, 0.3, 0.2)),
        Material("brass", (0.9, 0.6, 0.3), roughness=0.3, metallic=1.0)]
# (material, new colour, whether it is the material's first edit): its basis is binned then, not on its second.
EDITS = [(1, (0.5, 0.6, 0.2), True), (1, (0.3, 0.7, 0.2), False), (2, (0.5, 0.5, 0.9), None), (0, (0.2, 0.6, 0.7), True)]


def scene(materials):
    """A floor, a red box and a brass box under a point light and a grey sky."""
    m = np.eye(4)
    m[:3, 3] = (-1.5, -1.0, 3.0)
    floor = quad([(-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)], (0, 0, 1))
    quads = [(floor, 0)] + box_quads((-1.2, -0.5, 0.0), (-0.2, 0.5, 1.0), 1, inward=False) + \
        box_quads((0.4, -0.4, 0.0), (1.2, 0.4, 0.8), 2, inward=False)
    s = quad_scene(quads, materials, [Light("lamp", "POINT", (1.0, 0.9, 0.8), 60.0, m)], eye=(0.0, -7.0, 6.0),
                   target=(0.0, 0.0, 0.0), world=(0.2, 0.2, 0.2))
    s.resolution = (96, 72)
    return s


def test_a_colour_edit_rebins_only_the_change_and_matches_a_cold_render(engines, monkeypatch):
    from bounce_gi.gpu_kernels.settings import RenderSettings

    warm, cold = engines
    settings = RenderSettings(method="lpv", width=96, height=72, shadow=ShadowSettings(
        cube_resolution=128, sky_directions=64, sky_resolution=64))
    binned = []
    records = gather.rsm_records
    monkeypatch.setattr(gather, "rsm_records", lambda *a, **k: binned.append(k.get("change")) or records(*a, **k))
    materials = list(BASE)
    warm.render(scene(materials), settings)
    entries = warm.pipeline.cache.entries
    for index, colour, first_edit in EDITS:
        materials[index] = Material(materials[index].name, colour, roughness=materials[index].roughness,
                                    metallic=materials[index].metallic)
        binned.clear()
        result = warm.render(scene(materials), settings)
        metal = materials[index].metallic != 0
        assert {"shadow_maps", "rsm", "geometry_volume"} <= set(result.skipped)
        # a metal's Fresnel takes its colour: its direct light is lit again, a dielectric's is kept
        assert ("direct_light" in result.skipped) != metal and ("sky_visibility" in result.skipped) != metal
        first = entries["lpv_inject"].value
        assert first.recolored == 1 and first.binned == 0
        assert len(binned) == (1 if metal or first_edit else 0) and all(c is not None for c in binned)
        fresh = cold.render(scene(materials), settings)
        cold.clear_cache()
        for name in ("Diffuse Direct", "Glossy Direct"):
            np.testing.assert_array_equal(result.passes[name], fresh.passes[name], err_msg=name)
        for name in ("Diffuse Indirect", "Combined"):
            diff = np.abs(result.passes[name] - fresh.passes[name]).max()
            print(f"{materials[index].name} {colour}: {name} max |warm − cold| {diff:.2e}")
            assert diff <= BOUND * np.abs(fresh.passes[name]).max(), name
