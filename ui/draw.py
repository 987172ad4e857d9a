# SPDX-License-Identifier: GPL-3.0-or-later
"""Drawing the engine's surface light with Blender's `gpu` module: the one drawing path of Rendered shading
(render_engine.view_draw), the Solid-mode overlay (overlay.py) and `bounce-gi snapshot`.

A GI update's result (pipeline.SurfaceLight: the surface atlas's light and the triangles to draw) becomes a
SurfaceDrawing once, on the main thread: two 2D textures (direct and indirect light × base colour, each in its
own atlas) and one vertex batch. Blender's textures cannot be
updated in place, so a new result makes new ones and the old are freed. Drawing it from a camera runs no GI
pass: the fragment shader (gpu_kernels/shaders/viewport/surface.glsl) looks the light up per pixel.

Must run where Blender's `gpu` module draws: the main thread of an interactive Blender, or background mode after
one tiny Workbench render (ensure_gpu).
"""
from __future__ import annotations

from dataclasses import dataclass

import gpu
import numpy as np
from mathutils import Matrix

from ..gpu_kernels.gl.preprocessor import load
from ..gpu_kernels.surface.mesh import ATTRIBUTES

SHADER_FILE = "viewport/surface.glsl"
MODES = {"COMBINED": 0, "INDIRECT": 1, "DIRECT": 2}
GLSL_TYPES = {2: "VEC2", 3: "VEC3", 4: "VEC4"}
_shader = None


def stage_source(stage: str) -> str:
    """One stage of the viewport shader, includes expanded, without #version (Blender writes its own)."""
    text = load(SHADER_FILE, stage=stage).text
    return "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#version")) + "\n"


def surface_shader():
    """The viewport's surface shader (compiled once per Blender session)."""
    global _shader
    if _shader is None:
        iface = gpu.types.GPUStageInterfaceInfo("bounce_gi_surface_iface")
        for name, n in (("v_position", 3), ("v_normal", 3), ("v_tile", 2), ("v_tile_i", 2)):
            iface.smooth(GLSL_TYPES[n], name)
        for name, n in (("v_geo_normal", 3), ("v_box", 3), ("v_box_i", 3), ("v_mat", 3), ("v_emission", 3)):
            iface.flat(GLSL_TYPES[n], name)
        info = gpu.types.GPUShaderCreateInfo()
        for name, glsl_type in (("u_view_projection", "MAT4"), ("u_eye", "VEC4"), ("u_forward", "VEC4"),
                                ("u_params", "VEC4")):
            info.push_constant(glsl_type, name)
        for slot, name in enumerate(("u_direct", "u_indirect", "u_material_lut")):
            info.sampler(slot, "FLOAT_2D", name)
        for slot, (name, n) in enumerate(ATTRIBUTES):
            info.vertex_in(slot, GLSL_TYPES[n], name)
        info.vertex_out(iface)
        info.fragment_out(0, "VEC4", "out_color")
        info.vertex_source(stage_source("vertex"))
        info.fragment_source(stage_source("fragment"))
        _shader = gpu.shader.create_from_info(info)
    return _shader


def release_shader() -> None:
    """Forget the compiled shader (on unregister: a re-enabled extension compiles its own)."""
    global _shader
    _shader = None


def rgba_texture(pixels: np.ndarray):
    """An (H, W, 3|4) float array, rows bottom-up, as an RGBA32F GPUTexture with linear filtering. (Blender
    versions without GPUTexture.filter_mode sample the nearest texel: blockier, the same light.)"""
    h, w = pixels.shape[:2]
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :pixels.shape[2]] = pixels[..., :4]
    texture = gpu.types.GPUTexture((w, h), format="RGBA32F", data=gpu.types.Buffer("FLOAT", rgba.size, rgba.ravel()))
    if hasattr(texture, "filter_mode"):
        texture.filter_mode(True)
    return texture


def material_lut_of(light) -> np.ndarray:
    """The result's Principled table (rows of μ texels); results made before it existed get a Lambertian one."""
    lut = getattr(light, "material_lut", None)
    if lut is None:
        lut = np.ones((4, 2, 4), np.float32)
        lut[1:, :, :] = 0.0
    return lut


@dataclass
class View:
    """A camera for drawing: world → clip matrix (4 × 4, numpy, column vectors), eye position, unit view axis."""
    view_projection: np.ndarray
    eye: tuple
    forward: tuple
    ortho: bool = False


class SurfaceDrawing:
    """One GI result on the GPU, ready to be drawn from any view."""

    def __init__(self, light):
        from gpu_extras.batch import batch_for_shader

        coarse = light.indirect_atlas or light.atlas
        coarse_base = light.base if light.indirect_base is None else light.indirect_base
        self.page_heights = (int(light.atlas.height), int(coarse.height))
        # Both pages of an atlas show the same surfaces' colours.
        self.textures = {"u_direct": rgba_texture(light.direct * np.concatenate([light.base, light.base])),
                         "u_indirect": rgba_texture(light.indirect * np.concatenate([coarse_base, coarse_base])),
                         "u_material_lut": rgba_texture(material_lut_of(light))}
        self.triangles = len(light.mesh["pos"]) // 3
        self.batch = batch_for_shader(surface_shader(), "TRIS", light.mesh) if self.triangles else None

    def draw(self, view: View, mode: str = "COMBINED", depth_pull: float = 0.0) -> None:
        """Draw into the bound framebuffer, depth-tested (LESS_EQUAL) and depth-writing."""
        if self.batch is None:
            return
        shader = surface_shader()
        shader.bind()
        shader.uniform_float("u_view_projection", Matrix(np.asarray(view.view_projection, float).tolist()))
        shader.uniform_float("u_eye", (*view.eye, 1.0 if view.ortho else 0.0))
        shader.uniform_float("u_forward", (*view.forward, float(self.page_heights[0])))
        shader.uniform_float("u_params", (float(MODES[mode]), float(depth_pull), float(self.page_heights[1]), 0.0))
        for name, texture in self.textures.items():
            shader.uniform_sampler(name, texture)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        gpu.state.face_culling_set("NONE")
        self.batch.draw(shader)
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)

    def free(self) -> None:
        """Drop the textures and the batch (Blender frees GPU objects when their Python objects go)."""
        self.textures, self.batch = {}, None


def draw_offscreen(drawing: SurfaceDrawing | None, offscreen, view: View, background, mode="COMBINED") -> None:
    """Clear `offscreen` to the world colour and draw the surfaces into it: scene-linear values, no view transform
    (Rendered shading shows it through Blender's display-space shader)."""
    with offscreen.bind():
        fb = gpu.state.active_framebuffer_get()
        fb.clear(color=(*tuple(background)[:3], 1.0), depth=1.0)
        if drawing is not None:
            drawing.draw(view, mode)


def read_offscreen(offscreen) -> np.ndarray:
    """The offscreen's colour as (H, W, 4) float32, rows top-to-bottom (image order)."""
    w, h = offscreen.width, offscreen.height
    with offscreen.bind():
        buf = gpu.state.active_framebuffer_get().read_color(0, 0, w, h, 4, 0, "FLOAT")
    buf.dimensions = w * h * 4
    return np.asarray(buf, np.float32).reshape(h, w, 4)[::-1].copy()


def ensure_gpu() -> None:
    """In background mode Blender's gpu module draws only after one render has set it up (a Workbench render of
    8 × 8 pixels, on a scratch scene that is removed again); interactive Blender needs nothing."""
    import bpy

    if not bpy.app.background or getattr(ensure_gpu, "done", False):
        return
    scene = bpy.data.scenes.new("bounce_gi_gpu_init")
    camera = bpy.data.cameras.new("bounce_gi_gpu_init")
    obj = bpy.data.objects.new("bounce_gi_gpu_init", camera)
    try:
        scene.collection.objects.link(obj)
        scene.camera = obj
        scene.render.engine = "BLENDER_WORKBENCH"
        scene.render.resolution_x = scene.render.resolution_y = 8
        bpy.ops.render.render(scene=scene.name)
    finally:
        bpy.data.objects.remove(obj)
        bpy.data.cameras.remove(camera)
        bpy.data.scenes.remove(scene)
    ensure_gpu.done = True


def camera_view(camera, width: int, height: int, pixel_aspect=(1.0, 1.0)) -> View:
    """The View of a scene Camera at width × height: the projection the render uses (common/camera.py), so a
    snapshot and a render see the same pixels."""
    from ..gpu_kernels.common import camera as cam

    m = np.asarray(camera.matrix_world, np.float64)
    forward = -m[:3, 2] / np.linalg.norm(m[:3, 2])
    vp = cam.projection_matrix(camera, width, height, *pixel_aspect) @ cam.view_matrix(camera)
    return View(vp, tuple(m[:3, 3]), tuple(forward), camera.type == "ORTHO")


def snapshot(light, scene, width: int, height: int, mode: str = "COMBINED") -> np.ndarray:
    """What the viewport draws of `light` (a SurfaceLight of `scene`) from the scene camera, as (H, W, 4) float32
    rows top-to-bottom, scene-linear: the same shader and uploads as Rendered shading, into a GPUOffScreen."""
    ensure_gpu()
    drawing = SurfaceDrawing(light)
    offscreen = gpu.types.GPUOffScreen(width, height, format="RGBA32F")
    try:
        draw_offscreen(drawing, offscreen, camera_view(scene.camera, width, height, scene.pixel_aspect),
                       scene.world.color, mode)
        return read_offscreen(offscreen)
    finally:
        offscreen.free()
        drawing.free()
