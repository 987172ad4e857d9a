# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.common.camera reproduces Blender's camera exactly (docs/conventions.md, Camera: lens/sensor, sensor fit, shift, pixel
aspect, ortho scale, clip).

The reference is Blender itself: `Object.calc_matrix_camera(depsgraph, x, y, scale_x, scale_y)` (the projection
Blender builds from BKE_camera_params_compute_viewplane, including clip start/end) and `matrix_world.inverted()`.
All cameras are made in ONE bpy subprocess (bpy must not be imported into the test process: it is big, and
importing it here would let other tests' purity checks be fooled); it prints both Blender's matrices and the
camera values, and the test process builds `gpu_kernels.scene.Camera` from those values and compares.

Tolerance: 1e-5 relative to the largest entry of each matrix. Blender computes and returns these matrices in float32
(mathutils.Matrix holds floats, the view plane is computed in float), so agreement is limited to ~1e-7 relative per
operation, and a few operations stack; 1e-5 leaves headroom while a wrong sensor, fit or shift is off by ≥ 1e-2.
"""
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.scene import Camera

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RTOL = 1e-5

# id: (camera settings, width, height, pixel aspect x, pixel aspect y, location, rotation XYZ (deg))
CONFIGS = {
    "persp_auto_wide": (dict(type="PERSP", lens=35.0, sensor_fit="AUTO"), 640, 480, 1.0, 1.0,
                        (1.0, -6.0, 2.0), (80.0, 0.0, 10.0)),
    "persp_auto_tall": (dict(type="PERSP", lens=50.0, sensor_fit="AUTO", sensor_width=36.0, sensor_height=24.0),
                        480, 640, 1.0, 1.0, (0.5, -4.0, 1.5), (75.0, 5.0, -20.0)),
    "persp_horizontal_on_tall": (dict(type="PERSP", lens=28.0, sensor_fit="HORIZONTAL", sensor_width=30.0,
                                      sensor_height=20.0), 300, 500, 1.0, 1.0, (0, -5, 1), (90, 0, 0)),
    "persp_vertical_on_wide": (dict(type="PERSP", lens=42.0, sensor_fit="VERTICAL", sensor_width=36.0,
                                    sensor_height=18.0), 500, 300, 1.0, 1.0, (2, 3, 4), (30, -10, 140)),
    "persp_shift": (dict(type="PERSP", lens=50.0, sensor_fit="AUTO", shift_x=0.2, shift_y=-0.15,
                         clip_start=0.05, clip_end=250.0), 320, 200, 1.0, 1.0, (0, -7, 3), (70, 0, 0)),
    "persp_shift_tall": (dict(type="PERSP", lens=24.0, sensor_fit="AUTO", shift_x=-0.1, shift_y=0.3),
                         200, 320, 1.0, 1.0, (-3, -3, 2), (80, 0, -45)),
    "persp_pixel_aspect_2_1": (dict(type="PERSP", lens=50.0, sensor_fit="AUTO", shift_x=0.05),
                               320, 240, 2.0, 1.0, (0, -5, 1), (85, 0, 0)),
    # 200x300 with 2:1 pixels is 400 wide in display units: AUTO must pick HORIZONTAL although height > width.
    "persp_pixel_aspect_flips_auto_fit": (dict(type="PERSP", lens=35.0, sensor_fit="AUTO"),
                                          200, 300, 2.0, 1.0, (0, -5, 1), (85, 0, 0)),
    "persp_pixel_aspect_1_2": (dict(type="PERSP", lens=35.0, sensor_fit="VERTICAL", sensor_height=20.0),
                               300, 200, 1.0, 2.0, (0, -5, 1), (85, 0, 20)),
    "ortho_shift": (dict(type="ORTHO", ortho_scale=5.0, sensor_fit="AUTO", shift_x=0.1, shift_y=0.25,
                         clip_start=0.5, clip_end=40.0), 400, 300, 1.0, 1.0, (0, -10, 5), (60, 0, 15)),
    "ortho_vertical": (dict(type="ORTHO", ortho_scale=3.0, sensor_fit="VERTICAL", shift_y=-0.2),
                       480, 270, 1.0, 1.0, (4, 0, 2), (90, 0, 90)),
    "ortho_auto_tall_aspect": (dict(type="ORTHO", ortho_scale=8.0, sensor_fit="AUTO"),
                               240, 320, 1.0, 1.5, (0, 0, 10), (0, 0, 0)),
}

SCRIPT = textwrap.dedent("""
    import json, math, sys
    import bpy

    configs = json.loads(sys.argv[1])
    scene = bpy.context.scene
    out = {}
    for name, (settings, w, h, ax, ay, loc, rot) in configs.items():
        data = bpy.data.cameras.new(name)
        for key, value in settings.items():
            setattr(data, key, value)
        obj = bpy.data.objects.new(name, data)
        scene.collection.objects.link(obj)
        obj.location = loc
        obj.rotation_euler = [math.radians(a) for a in rot]
        dg = bpy.context.evaluated_depsgraph_get()
        dg.update()
        proj = obj.calc_matrix_camera(dg, x=w, y=h, scale_x=ax, scale_y=ay)
        out[name] = {
            "projection": [list(r) for r in proj],
            "view": [list(r) for r in obj.matrix_world.inverted()],
            "matrix_world": [list(r) for r in obj.matrix_world],
            "camera": {k: getattr(data, k) for k in ("type", "lens", "sensor_width", "sensor_height", "sensor_fit",
                                                      "ortho_scale", "shift_x", "shift_y", "clip_start", "clip_end")},
        }
    print("JSON" + json.dumps(out))
""")


@pytest.fixture(scope="module")
def blender():
    proc = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(CONFIGS)], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    line = next(l for l in proc.stdout.splitlines() if l.startswith("JSON"))
    return json.loads(line[4:])


def _camera(entry) -> Camera:
    return Camera(matrix_world=np.array(entry["matrix_world"], np.float64), **entry["camera"])


def _assert_close(ours, theirs, what):
    ours, theirs = np.asarray(ours, np.float64), np.asarray(theirs, np.float64)
    scale = np.abs(theirs).max()
    err = np.abs(ours - theirs).max() / scale
    assert err <= RTOL, f"{what}: max rel error {err:.3g}\nours:\n{ours}\nBlender:\n{theirs}"


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_projection_matches_blender(blender, name):
    entry = blender[name]
    _, w, h, ax, ay, _, _ = CONFIGS[name]
    # The camera values went through Blender (float32) and came back: the ones we asked for must be the ones used.
    settings = CONFIGS[name][0]
    for key, value in settings.items():
        got = entry["camera"][key]
        assert got == value if isinstance(value, str) else abs(got - value) < 1e-5, (key, got, value)
    proj = cam.projection_matrix(_camera(entry), w, h, ax, ay)
    _assert_close(proj, entry["projection"], f"{name} projection")


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_view_matrix_matches_blender(blender, name):
    entry = blender[name]
    view = cam.view_matrix(_camera(entry))
    _assert_close(view, entry["view"], f"{name} view")
    # And it is the inverse of matrix_world to float64 precision (the camera's own definition).
    assert np.allclose(view @ np.array(entry["matrix_world"]), np.eye(4), atol=1e-12)


@pytest.mark.parametrize("name", ["persp_shift", "ortho_shift", "persp_auto_wide"])
def test_clip_planes_land_on_ndc_depth_limits(blender, name):
    """Blender's projection includes clip start/end; ours must put them at NDC z = -1 and +1 (OpenGL)."""
    entry = blender[name]
    c = _camera(entry)
    _, w, h, ax, ay, _, _ = CONFIGS[name]
    # Ours is float64 (tight); Blender's is float32 (looser).
    for matrix, tol in ((cam.projection_matrix(c, w, h, ax, ay), 1e-9), (np.array(entry["projection"]), 1e-4)):
        for dist, ndc_z in ((c.clip_start, -1.0), (c.clip_end, 1.0)):
            clip = matrix @ np.array([0.0, 0.0, -dist, 1.0])
            assert clip[2] / clip[3] == pytest.approx(ndc_z, abs=tol)


def test_view_plane_pixel_footprint_matches_lens_formula():
    """Independent of Blender: a 50 mm lens on a 36 mm sensor, HORIZONTAL fit, 200 px wide, shift 0.25:
    the plane at distance 1 spans 36/50 = 0.72 m across and is moved right by 0.25·0.72."""
    c = Camera(matrix_world=np.eye(4), lens=50.0, sensor_width=36.0, sensor_height=24.0, sensor_fit="HORIZONTAL",
               shift_x=0.25, shift_y=0.0)
    l, r, b, t = cam.view_plane(c, 200, 100)
    assert (l, r) == pytest.approx((-0.36 + 0.18, 0.36 + 0.18))
    assert (b, t) == pytest.approx((-0.18, 0.18))  # square pixels: height follows from the width
    # Pixel centre (i + 0.5) of the leftmost column projects to NDC x = -1 + 1/W.
    p = cam.projection_matrix(c, 200, 100)
    x_world = l + (0.5 / 200) * (r - l)
    clip = p @ np.array([x_world * 3.0, 0.0, -3.0, 1.0])
    assert clip[0] / clip[3] == pytest.approx(-1 + 1 / 200)
