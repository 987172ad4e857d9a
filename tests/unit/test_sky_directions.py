# SPDX-License-Identifier: GPL-3.0-or-later
"""The sky light's records (common/lights.py): its directions cover the sphere evenly, and a lit world becomes one
LIGHT_SKY record with one hard-shadowed orthographic view per direction; a black world adds none."""
import math

import numpy as np

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.common import atlas
from bounce_gi.gpu_kernels.common import lights as lb
from bounce_gi.gpu_kernels.scene import Material
from support.synthetic import box_quads, quad_scene


def test_the_directions_integrate_the_cosine_over_a_hemisphere():
    """Σ_k max(0, n·d_k)·4π/K is the quadrature of ∫ max(0, n·ω) dω = π, the sky's unshadowed irradiance per unit
    radiance, for any n. The lattice's error for K = 384: measured under 0.1% for the six axes and a skew normal;
    bound 0.5% — a lattice clumped toward the poles or a wrong solid angle per direction errs by far more."""
    d = cam.sphere_directions(384)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)
    for n in [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1), (0.3, -0.5, 0.81)]:
        n = np.asarray(n, float) / np.linalg.norm(n)
        total = np.clip(d @ n, 0, None).sum() * 4 * math.pi / len(d)
        assert abs(total / math.pi - 1) < 0.005, (n, total / math.pi)


def _scene(world):
    return quad_scene(box_quads((-1, -1, 0), (1, 1, 2), 0), [Material("white", (0.8, 0.8, 0.8))], [],
                      (0, 0, 1), (1, 0, 1), world=world)


def test_a_lit_world_is_one_sky_light_with_a_view_per_direction():
    s = lb.ShadowSettings(sky_directions=64, sky_resolution=128)
    buffers = lb.build_light_buffers(_scene((0.2, 0.3, 0.4)), s)
    sky = [i for i, r in enumerate(buffers.lights) if int(r["color_type"][3]) == lb.LIGHT_SKY]
    assert len(sky) == 1
    rec = buffers.lights[sky[0]]
    np.testing.assert_allclose(rec["color_type"][:3], (0.2, 0.3, 0.4), rtol=1e-6)
    views = [v for v, light in zip(buffers.views, buffers.view_lights) if light == sky[0]]
    assert len(views) == rec["params"][2] == 64 and rec["params"][3] == 1
    assert all(v.ortho and v.resolution == 128 and v.pcf_radius == 0 for v in views)
    assert abs(sum(v.emit_share for v in views) - 4 * math.pi) < 1e-9
    packed = atlas.pack_views(buffers.views, [(0, 0, 128, 128)] * len(buffers.views), (4096, 4096), 1,
                           buffers.view_lights)
    assert (packed["info"][:, 1] == 0).all()  # the sky's maps: no PCF (direct/eval.glsl reads 4 texels' min)
    assert not any(int(r["color_type"][3]) == lb.LIGHT_SKY
                   for r in lb.build_light_buffers(_scene((0.0, 0.0, 0.0)), s).lights)
