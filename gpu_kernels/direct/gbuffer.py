# SPDX-License-Identifier: GPL-3.0-or-later
"""The G-buffer: the scene rasterised from its camera into position, normal, albedo, emission, geometric normal
and glossy colour targets (direct/gbuffer.glsl)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common import camera as cam
from ..gl.bind import set_uniform, write_uniform
from ..scene import Scene
from .geometry import GeometryBuffers, draw_by_material
from .shadows import box_rects

GBUFFER_TARGETS = ("position", "normal", "albedo", "emission", "geo_normal", "glossy", "specular")


@dataclass
class GBuffer:
    textures: dict  # name -> RGBA32F texture
    depth: object
    fbo: object
    size: tuple
    # The camera the G-buffer was rendered from (view directions for the VCT specular cone): world position, unit
    # view axis, orthographic flag.
    eye: tuple = (0.0, 0.0, 0.0)
    forward: tuple = (0.0, 0.0, -1.0)
    ortho: bool = False
    # World → clip (float64 4 × 4, OpenGL) where the G-buffer is a camera's view; None for the viewport's
    # surface atlas. vct/reuse.py projects the last view's samples with it.
    view_projection: object = None

    def release(self):
        self.fbo.release()
        self.depth.release()
        for t in self.textures.values():
            t.release()


def render_gbuffer(ctx, programs, scene: Scene, geometry: GeometryBuffers, textures: list,
                   width: int, height: int) -> GBuffer:
    """Rasterise the scene from its camera into the G-buffer targets (rows bottom-up, GL order)."""
    import moderngl

    camera = scene.camera
    targets = {name: ctx.texture((width, height), 4, dtype="f4") for name in GBUFFER_TARGETS}
    for t in targets.values():
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    depth = ctx.depth_renderbuffer((width, height))
    fbo = ctx.framebuffer(color_attachments=[targets[n] for n in GBUFFER_TARGETS], depth_attachment=depth)
    fbo.use()
    fbo.viewport = (0, 0, width, height)
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.disable(moderngl.CULL_FACE)
    aspect = scene.pixel_aspect
    view = cam.view_matrix(camera)
    proj = cam.projection_matrix(camera, width, height, aspect[0], aspect[1])
    prog = programs.raster("direct/gbuffer.glsl")
    cam_world = np.asarray(camera.matrix_world, np.float64)
    forward = -cam_world[:3, 2] / np.linalg.norm(cam_world[:3, 2])
    write_uniform(prog, "u_view_projection", (proj @ view).T)
    set_uniform(prog, "u_camera_position", tuple(cam_world[:3, 3]))
    set_uniform(prog, "u_camera_forward", tuple(forward))
    set_uniform(prog, "u_camera_ortho", camera.type == "ORTHO")
    draw_by_material(prog, scene, geometry, textures)
    return GBuffer(targets, depth, fbo, (width, height), tuple(float(c) for c in cam_world[:3, 3]),
                   tuple(float(c) for c in forward), camera.type == "ORTHO", proj @ view)


def box_pixels(scene: Scene, width: int, height: int, box: np.ndarray) -> tuple:
    """The G-buffer pixels (x0, y0, x1, y1; GL order, rows from the bottom, x1 and y1 excluded) that triangles
    inside the world `box` (2, 3) can cover: the box clipped to the camera's near plane and projected, grown by
    shadows.MOVED_MARGIN pixels (shadows.box_rects, as a shadow map's redrawn rectangle); (0, 0, 0, 0) for none."""
    aspect = scene.pixel_aspect
    view_projection = cam.projection_matrix(scene.camera, width, height, aspect[0], aspect[1]) @ \
        cam.view_matrix(scene.camera)
    rect = box_rects(view_projection[None], box, [(0, 0, width, height)])[0]
    return (0, 0, 0, 0) if rect is None else (rect[0], rect[1], rect[0] + rect[2], rect[1] + rect[3])
