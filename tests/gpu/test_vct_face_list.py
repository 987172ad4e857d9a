# SPDX-License-Identifier: GPL-3.0-or-later
"""The VCT bounce gathers run over a list of the voxel faces with coverage (vct/bounce.face_list, vct/bounce.glsl
MODE_LIST): the list holds each face whose coverage α > 0 exactly once, read back against the injected face
volumes, also when it had to be made again larger than its first guess."""
import numpy as np

from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Light, Material
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.vct import bounce
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from bounce_gi.gpu_kernels.vct.trace import read_level
from support.synthetic import box_quads, quad_scene


def _room():
    bulb = np.eye(4)
    bulb[:3, 3] = (-0.3, 0.2, 1.5)
    quads = box_quads((-1, -1, 0), (1, 1, 2), 0) + box_quads((-0.3, -0.3, 0.0), (0.3, 0.3, 0.7), 1, inward=False)
    return quad_scene(quads, [Material("white", (0.7, 0.7, 0.7)), Material("red", (0.8, 0.2, 0.1))],
                      [Light("bulb", "POINT", (1, 1, 1), 60.0, bulb)], (0.0, -0.9, 1.5), (0.0, 0.5, 0.3))


def test_the_face_list_holds_every_face_with_coverage_once():
    engine = Engine()
    try:
        engine.render(_room(), RenderSettings("vct", 40, 30, vct=VctSettings(resolution=32)))
        pipe = engine.pipeline

        def grab(ctx):
            faces = pipe.cache.entries["vct_inject"].value
            alpha = np.stack([read_level(ctx, pipe.programs, t, faces.grid, 0)[..., 3] for t in faces.textures])
            lists = []
            for capacity in (None, 1):  # six per occupied voxel; one, so that it is made again
                listed, count = bounce.face_list(ctx, pipe.programs, faces, capacity)
                lists.append(np.frombuffer(listed.read(), np.int32)[:4 * count].reshape(count, 4))
                listed.release()
            return alpha, faces.occupied, lists
        alpha, occupied, lists = engine.worker.call(grab)
    finally:
        engine.shutdown()
    g, z, y, x = np.nonzero(alpha > 0)
    want = np.stack([x, y, z, g], axis=1)
    assert len(want) > 1000 and occupied > 0 and len(want) <= 6 * occupied
    for got in lists:
        assert len(got) == len(want)
        assert np.array_equal(np.unique(got, axis=0), np.unique(want, axis=0))  # each once, in any order
