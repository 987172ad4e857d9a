# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender's camera, reproduced exactly: view matrix, view plane and the OpenGL projection.

The view plane follows Blender's `BKE_camera_params_compute_viewplane` (source/blender/blenkernel/intern/camera.cc),
which Cycles mirrors (intern/cycles/blender/camera.cpp): the sensor dimension used is picked by the sensor fit,
lens shift is in units of the fitted dimension, and pixel aspect scales the vertical extent. Pixel (i, j) covers
[i, i+1] × [j, j+1] of the view plane, sampled at its centre — the same as OpenGL rasterisation, and the same as
Cycles with a ~0.01 px pixel filter (the reference settings in docs/conventions.md).
"""
from __future__ import annotations

import math

import numpy as np

from ..scene import Camera


def sensor_fit_of(camera: Camera, width: int, height: int, aspect_x: float = 1.0, aspect_y: float = 1.0) -> str:
    """'HORIZONTAL' or 'VERTICAL': AUTO fits the larger image dimension (BKE_camera_sensor_fit)."""
    if camera.sensor_fit == "AUTO":
        return "HORIZONTAL" if aspect_x * width >= aspect_y * height else "VERTICAL"
    return camera.sensor_fit


def view_plane(camera: Camera, width: int, height: int, aspect_x: float = 1.0, aspect_y: float = 1.0):
    """(xmin, xmax, ymin, ymax) of the view plane at distance 1 (perspective) or in metres (orthographic)."""
    ycor = aspect_y / aspect_x
    fit = sensor_fit_of(camera, width, height, aspect_x, aspect_y)
    if camera.type == "ORTHO":
        pixsize = camera.ortho_scale
    else:
        # AUTO and HORIZONTAL use sensor_width (BKE_camera_sensor_size); at distance 1 instead of clip_start.
        sensor = camera.sensor_height if camera.sensor_fit == "VERTICAL" else camera.sensor_width
        pixsize = sensor / camera.lens
    viewfac = width if fit == "HORIZONTAL" else ycor * height
    pixsize /= viewfac
    dx = camera.shift_x * viewfac
    dy = camera.shift_y * viewfac
    xmin, xmax = -0.5 * width + dx, 0.5 * width + dx
    ymin, ymax = -0.5 * ycor * height + dy, 0.5 * ycor * height + dy
    return xmin * pixsize, xmax * pixsize, ymin * pixsize, ymax * pixsize


def view_matrix(camera: Camera) -> np.ndarray:
    """World → camera space (camera looks down -Z, +Y up), float64."""
    return np.linalg.inv(np.asarray(camera.matrix_world, np.float64))


def projection_matrix(camera: Camera, width: int, height: int, aspect_x: float = 1.0,
                      aspect_y: float = 1.0) -> np.ndarray:
    """OpenGL clip-space projection (float64) whose NDC square is exactly Blender's view plane."""
    l, r, b, t = view_plane(camera, width, height, aspect_x, aspect_y)
    n, f = camera.clip_start, camera.clip_end
    if camera.type == "ORTHO":
        return ortho(l, r, b, t, n, f)
    return frustum(l * n, r * n, b * n, t * n, n, f)


def frustum(l, r, b, t, n, f) -> np.ndarray:
    return np.array([
        [2 * n / (r - l), 0, (r + l) / (r - l), 0],
        [0, 2 * n / (t - b), (t + b) / (t - b), 0],
        [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)],
        [0, 0, -1, 0],
    ], np.float64)


def ortho(l, r, b, t, n, f) -> np.ndarray:
    return np.array([
        [2 / (r - l), 0, 0, -(r + l) / (r - l)],
        [0, 2 / (t - b), 0, -(t + b) / (t - b)],
        [0, 0, -2 / (f - n), -(f + n) / (f - n)],
        [0, 0, 0, 1],
    ], np.float64)


def perspective(fov_y: float, aspect: float, n: float, f: float) -> np.ndarray:
    t = n * np.tan(fov_y / 2)
    return frustum(-t * aspect, t * aspect, -t, t, n, f)


def _cross(a, b) -> tuple:
    """a × b of two 3-vectors, in plain floats: np.cross costs tens of microseconds a call, and the shadow views
    of a scene's lights take thousands of these (six per emitter or area-light sample, one per sky direction)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _unit(v) -> tuple:
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return (v[0] / n, v[1] / n, v[2] / n)


def look_at(eye, target, up) -> np.ndarray:
    """World → view matrix looking from `eye` at `target` (float64)."""
    eye, target, up = ([float(c) for c in v] for v in (eye, target, up))
    fwd = _unit([t - e for t, e in zip(target, eye)])
    side = _cross(fwd, up)
    if math.sqrt(sum(c * c for c in side)) < 1e-8:  # looking along `up`: pick another up
        side = _cross(fwd, (1.0, 0.0, 0.0) if abs(fwd[0]) < 0.9 else (0.0, 1.0, 0.0))
    side = _unit(side)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = side, _cross(side, fwd), [-c for c in fwd]
    m[:3, 3] = -m[:3, :3] @ np.asarray(eye)
    return m


def sphere_directions(count: int) -> np.ndarray:
    """`count` unit vectors spread evenly over the sphere (a spherical Fibonacci lattice: equal-area bands, golden
    angle in longitude), each standing for a solid angle of 4π/count."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
