# SPDX-License-Identifier: GPL-3.0-or-later
"""The scene camera and the render size: `gpu_kernels.scene.Camera` from the active camera object."""
from __future__ import annotations

import numpy as np

from ...gpu_kernels.scene import Camera
from .errors import ExtractError


def read_camera(scene) -> Camera:
    """The scene's active camera; ExtractError when there is none or its type is not supported."""
    cam_obj = scene.camera
    if cam_obj is None:
        raise ExtractError("the scene has no camera")
    data = cam_obj.data
    if data.type not in ("PERSP", "ORTHO"):
        raise ExtractError(f"camera '{cam_obj.name}' is {data.type}; only perspective and orthographic are supported")
    m = np.array(cam_obj.matrix_world, np.float64)
    for i in range(3):  # the camera's scale does not change Blender's projection
        m[:3, i] /= np.linalg.norm(m[:3, i])
    return Camera(matrix_world=m, type=data.type, lens=float(data.lens), sensor_width=float(data.sensor_width),
                  sensor_height=float(data.sensor_height), sensor_fit=data.sensor_fit,
                  ortho_scale=float(data.ortho_scale), shift_x=float(data.shift_x), shift_y=float(data.shift_y),
                  clip_start=float(data.clip_start), clip_end=float(data.clip_end))


def render_resolution(render, resolution=None) -> tuple[int, int]:
    """`resolution` (W, H) if given, else the scene's render size after its resolution percentage, in integers as
    Blender computes it (size · percentage / 100, rounded down: 100 px at 29 % is 29 px, where 100 · 0.29 in floats
    is 28.999…)."""
    if resolution is None:
        pct = render.resolution_percentage
        resolution = (max(1, render.resolution_x * pct // 100), max(1, render.resolution_y * pct // 100))
    return tuple(int(v) for v in resolution)


def pixel_aspect(render) -> tuple[float, float]:
    return float(render.pixel_aspect_x), float(render.pixel_aspect_y)
