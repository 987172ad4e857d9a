# SPDX-License-Identifier: GPL-3.0-or-later
"""Every shader program the pipeline compiles fits the resource limits of real GPU drivers, not only llvmpipe's.

Why: llvmpipe (the CI renderer) allows 32 image units per stage, NVIDIA's driver 8 — the OpenGL 4.3 minimum
(GL_MAX_COMPUTE_IMAGE_UNIFORMS / GL_MAX_FRAGMENT_IMAGE_UNIFORMS). vct/inject.glsl once bound twelve images and VCT
passed every test here but did not compile on an H200 ("invalid value 6 (array size 6) for layout specifier
'binding'"). So: render with settings that reach every program variant, then count each program's image and
sampler uniforms (array elements included) from the linked program. Samplers are held to 32, what NVIDIA, AMD,
Intel and Mesa drivers all give per stage (the spec's minimum is 16; lpv/octree_merge.glsl uses 20, vct/bounce.glsl
19).
"""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.lpv.settings import LpvSettings
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.synthetic import quad, quad_scene

MAX_IMAGES = 8
MAX_SAMPLERS = 32

# GL type enums (glcorearb.h): images 0x904C–0x906C; samplers 0x8B5D–0x8B64, 0x8DC0–0x8DD8, 0x900C–0x900F,
# 0x9108–0x910D.
_IMAGE_TYPES = range(0x904C, 0x906D)
_SAMPLER_TYPES = [*range(0x8B5D, 0x8B65), *range(0x8DC0, 0x8DD9), *range(0x900C, 0x9010), *range(0x9108, 0x910E)]


def _units(program):
    images = samplers = 0
    for name in program:
        member = program[name]
        gl_type = getattr(member, "gl_type", None)
        if gl_type in _IMAGE_TYPES:
            images += member.array_length
        elif gl_type in _SAMPLER_TYPES:
            samplers += member.array_length
    return images, samplers


def _room():
    """A lit corner with every light type and a glossy floor, so every light and specular variant compiles."""
    sun = Light("sun", "SUN", (1, 1, 1), 3.0, np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1.0]]))
    point = Light("point", "POINT", (1, 1, 1), 50.0, np.array([[1, 0, 0, 0], [0, 1, 0, -1], [0, 0, 1, 1.5],
                                                                  [0, 0, 0, 1.0]]))
    spot = Light("spot", "SPOT", (1, 1, 1), 50.0, np.array([[1, 0, 0, 1], [0, 1, 0, -1], [0, 0, 1, 1.8],
                                                               [0, 0, 0, 1.0]]))
    area = Light("area", "AREA", (1, 1, 1), 50.0, np.array([[1, 0, 0, -1], [0, 1, 0, 0], [0, 0, 1, 1.9],
                                                               [0, 0, 0, 1.0]]))
    floor = quad([(-2, -2, 0), (2, -2, 0), (2, 1, 0), (-2, 1, 0)], (0, 0, 1))
    wall = quad([(-2, 1, 0), (2, 1, 0), (2, 1, 2), (-2, 1, 2)], (0, -1, 0))
    lamp = quad([(1.5, 0.5, 0.2), (1.9, 0.5, 0.2), (1.9, 0.9, 0.2), (1.5, 0.9, 0.2)], (0, 0, 1))
    materials = [Material("floor", (0.5, 0.5, 0.5), roughness=0.1, specular_layer=True), Material("wall"),
                 Material("lamp", (0, 0, 0), emission=(4.0, 4.0, 4.0))]
    return quad_scene([(floor, 0), (wall, 1), (lamp, 2)], materials, [sun, point, spot, area], (0, -4, 1.2),
                  (0, 0.5, 0.2), world=(0.1, 0.1, 0.1), lens=20.0)


SETTINGS = [
    RenderSettings("none", 48, 36),
    RenderSettings("lpv", 48, 36, lpv=LpvSettings(resolution=16, cascades=3, bounces=2, damping=True)),
    RenderSettings("lpv", 48, 36, lpv=LpvSettings(resolution=16, octree_levels=2, rsm_downsample=2)),
    RenderSettings("vct", 48, 36, vct=VctSettings(resolution=16, bounces=4, gathered_bounces=2)),
    RenderSettings("vct", 48, 36, vct=VctSettings(resolution=16, bounces=2, anisotropic=False, indirect_scale=2,
                                                  temporal_frames=2)),
]


@pytest.fixture(scope="module")
def programs():
    engine = Engine()
    scene = _room()
    for settings in SETTINGS:
        engine.render(scene, settings)
    cache = engine.pipeline.programs
    return engine.worker.call(lambda ctx: {key: _units(p) for key, p in cache._programs.items()})


def test_every_program_fits_the_driver_minimums(programs):
    names = {key[1] for key in programs}
    # the check only means something if the render reached the heavy programs
    for expected in ("vct/inject.glsl", "vct/bounce.glsl", "vct/mipmap.glsl", "lpv/propagate.glsl",
                     "lpv/lighting.glsl"):
        assert expected in names, (expected, sorted(names))
    too_many = {key: units for key, units in programs.items() if units[0] > MAX_IMAGES or units[1] > MAX_SAMPLERS}
    assert not too_many, f"(images, samplers) over ({MAX_IMAGES}, {MAX_SAMPLERS}): {too_many}"


def test_the_counter_sees_image_arrays(programs):
    # vct/bounce.glsl writes six face images (an image3D[6]); a counter that saw 0 or 1 would pass anything
    bounce = [units for key, units in programs.items() if key[1] == "vct/bounce.glsl"]
    assert bounce and max(u[0] for u in bounce) == 6
