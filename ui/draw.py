# SPDX-License-Identifier: GPL-3.0-or-later
"""Drawing the engine's surface light with Blender's `gpu` module: the one drawing path of Rendered shading
(render_engine.view_draw), the Solid-mode overlay (overlay.py) and `bounce-gi snapshot`.

A GI update's result (pipeline.SurfaceLight: the surface atlas's light and the triangles to draw) becomes a
SurfaceDrawing once, on the main thread: two 2D textures (direct and indirect light × base colour, each in its
own atlas), the materials' diffuse-share rows and the vertex batches. Blender's textures cannot be updated in
place, so a new result makes new ones and the old are freed. Drawing it from a camera runs no GI
pass: the fragment shader (gpu_kernels/shaders/viewport/surface.glsl) looks the light up per pixel.

The triangles are drawn in a batch per shader variant (draw_parts.py): those whose material's diffuse share is
the same from every view (Diffuse BSDF, Principled without a specular layer) skip the per-pixel lookup of the
share, a fifth of a full-screen redraw on llvmpipe (benchmarks/results/viewport_llvmpipe.md); of the others, those
whose share a polynomial in μ fits evaluate it instead of sampling the table; triangles with one normal get it
flat. Each variant is compiled per display mode, when first drawn, and a redraw of a small mesh draws the
triangles facing the camera before the others.

Must run where Blender's `gpu` module draws: the main thread of an interactive Blender, or background mode after
one tiny Workbench render (ensure_gpu).
"""
from __future__ import annotations

from dataclasses import dataclass

import gpu
import numpy as np
from mathutils import Matrix

from ..gpu_kernels.common.principled import share_polynomial
from ..gpu_kernels.gl.preprocessor import load
from .draw_parts import CONSTANT, GREY, POLY, TABLE, share_rows, split_mesh

SHADER_FILE = "viewport/surface.glsl"
# Display mode → the light its shader adds up (a variant each: no fragment multiplies by a weight of 0 or 1).
MODES = {"COMBINED": ("DIRECT_LIGHT", "INDIRECT_LIGHT"), "INDIRECT": ("INDIRECT_LIGHT",), "DIRECT": ("DIRECT_LIGHT",)}
GLSL_TYPES = {2: "VEC2", 3: "VEC3", 4: "VEC4"}
SHARE_DEFINES = {CONSTANT: ("CONSTANT_SHARE",), GREY: ("POLY_SHARE", "GREY_SHARE"), POLY: ("POLY_SHARE",),
                 TABLE: ()}
# A material's share is drawn from its polynomial where that is this close to the table everywhere: a tenth of the
# 0.01 within which Diffuse Color counts as matching Cycles', below what a half-float framebuffer keeps of a
# share near 1 (2⁻¹¹ ≈ 5·10⁻⁴, twice that at most over the light it multiplies).
POLY_TOLERANCE = 1e-3
# Vertex inputs (surface/mesh.draw_arrays's, but `mat`): `material` is the CONSTANT variant's share (rgb) and the
# others' row in the part's share table or polynomial texture (a), one buffer for all variants.
SHARED_INPUTS = (("pos", 3), ("geo", 3), ("tile", 2), ("box", 3), ("tile_i", 2), ("box_i", 3), ("emission", 3),
                 ("material", 4))
ATLASES = (("u_direct", "FLOAT_2D"), ("u_indirect", "FLOAT_2D"))
POLY_SAMPLER, TABLE_SAMPLER = ("u_share_poly", "FLOAT_2D"), ("u_material_lut", "FLOAT_1D_ARRAY")
SHARE_SAMPLERS = {CONSTANT: (), GREY: (POLY_SAMPLER,), POLY: (POLY_SAMPLER,), TABLE: (TABLE_SAMPLER,)}
# The polynomial's coefficients, two vec4s a channel, handed on flat: of the red channel alone where all are grey.
SHARE_OUTPUTS = {CONSTANT: (), GREY: (("v_r0", 4), ("v_r1", 4)), TABLE: (),
                 POLY: tuple((f"v_{c}{k}", 4) for c in "rgb" for k in (0, 1))}
# Up to this many triangles a redraw draws those facing the camera in a pass before the others, so most back
# faces fail the depth test unshaded. llvmpipe culls after the vertex shader, so the second pass shades every
# vertex again: 0.2 ms per 1000 triangles with one core taken, which the saved fragments repay at 960×540 up to
# about 15 000 (measured, one core taken: −1.5 ms on the furnished room's 830 triangles, −0.6 with a 4 800-triangle
# sphere added to default_principled, ±0 at 15 500, +1.8 ms at 41 000, +7.8 ms at 95 000).
FRONT_FIRST_TRIANGLES = 10_000
_shaders = {}


def interface(share: str, flat: bool) -> tuple:
    """(vertex inputs beyond SHARED_INPUTS, samplers, smooth and flat outputs beyond the shared) of a variant."""
    samplers = (*ATLASES, *SHARE_SAMPLERS[share])
    if share == CONSTANT:
        return (), samplers, (), (("v_page", 2), ("v_share", 3))
    smooth, flat_out = [("v_view", 3)], [("v_page", 4)]
    (flat_out if flat else smooth).append(("v_normal", 3))
    return (("nrm", 3),), samplers, tuple(smooth), (*flat_out, *SHARE_OUTPUTS[share])


def variant_defines(share: str, flat: bool, mode: str) -> dict:
    """The #defines of a variant (viewport/surface.glsl names them)."""
    flat_normal = ("FLAT_NORMAL",) if flat and share != CONSTANT else ()
    return {name: None for name in (*SHARE_DEFINES[share], *flat_normal, *MODES[mode])}


def stage_source(stage: str, share: str = TABLE, flat: bool = False, mode: str = "COMBINED") -> str:
    """One stage of the viewport shader, includes expanded, without #version (Blender writes its own)."""
    text = load(SHADER_FILE, defines=variant_defines(share, flat, mode), stage=stage).text
    return "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#version")) + "\n"


def vertex_inputs(share: str, flat: bool = False) -> list:
    """(name, components) of the variant's vertex attributes, in declaration order."""
    return [*SHARED_INPUTS, *interface(share, flat)[0]]


def surface_shader(share: str = TABLE, flat: bool = False, mode: str = "COMBINED"):
    """The viewport's surface shader of one variant (compiled once per Blender session, when first drawn)."""
    key = (share, flat, mode)
    if key not in _shaders:
        _, samplers, smooth, flat_out = interface(share, flat)
        iface = gpu.types.GPUStageInterfaceInfo(f"bounce_gi_surface_{share}_{int(flat)}_{mode.lower()}_iface")
        for name, n in (("v_tile", 2), ("v_tile_i", 2), *smooth):
            iface.smooth(GLSL_TYPES[n], name)
        for name, n in (("v_clamp", 4), ("v_clamp_i", 4), ("v_emission", 3), *flat_out):
            iface.flat(GLSL_TYPES[n], name)
        info = gpu.types.GPUShaderCreateInfo()
        for name, glsl_type in (("u_view_projection", "MAT4"), ("u_eye", "VEC4"), ("u_forward", "VEC4"),
                                ("u_pages", "VEC2")):
            info.push_constant(glsl_type, name)
        for slot, (name, sampler_type) in enumerate(samplers):
            info.sampler(slot, sampler_type, name)
        for slot, (name, n) in enumerate(vertex_inputs(share, flat)):
            info.vertex_in(slot, GLSL_TYPES[n], name)
        info.vertex_out(iface)
        info.fragment_out(0, "VEC4", "out_color")
        info.vertex_source(stage_source("vertex", share, flat, mode))
        info.fragment_source(stage_source("fragment", share, flat, mode))
        _shaders[key] = gpu.shader.create_from_info(info)
    return _shaders[key]


def shaders_to_compile(drawing) -> list:
    """The (share, flat, mode) variants `drawing` would draw in some display mode that are not compiled yet."""
    variants = dict.fromkeys(variant for variant, _, _ in getattr(drawing, "parts", ()))
    return [(*variant, mode) for variant in variants for mode in MODES if (*variant, mode) not in _shaders]


_warmed = set()  # (share, flat, mode) drawn once into _warm_target
_warm_target = None  # the 1×1 warm-up buffer, made at the first warm-up draw


def compile_next_shader(drawing) -> bool:
    """Compile, then draw once into a 1×1 buffer like the 3D view's, one variant `drawing` may need in some display
    mode (shaders_to_compile); whether any is left. Called from a timer after a result is shown, one a tick, so that
    switching the display mode later draws at once: on llvmpipe a variant compiled at its first draw stalled the
    first switch to Direct or Indirect, and one compiled but never drawn still did, the driver building its code
    for the framebuffer at the first draw (measured: benchmarks/results/viewport_llvmpipe.md)."""
    missing = shaders_to_compile(drawing)
    if missing:
        surface_shader(*missing[0])
        return True
    cold = cold_variants(drawing)
    if cold:
        warm_variant(drawing, *cold[0])
    return len(cold) > 1


def cold_variants(drawing, modes=MODES) -> list:
    """The (variant, mode) pairs of `drawing`'s parts in `modes` not yet drawn into the warm-up buffer."""
    variants = dict.fromkeys(part[0] for part in getattr(drawing, "parts", ()))
    return [(variant, mode) for variant in variants for mode in modes if (*variant, mode) not in _warmed]


def warm_variant(drawing, variant, mode) -> None:
    """Draw `drawing`'s part of `variant` once in display mode `mode` into a 1×1 RGBA16F buffer (the 3D view's
    colour format), so that the driver has built its code for such a framebuffer before a redraw needs it."""
    global _warm_target
    if _warm_target is None:
        _warm_target = gpu.types.GPUOffScreen(1, 1, format="RGBA16F")
    part = next(p for p in drawing.parts if p[0] == variant)
    test, mask = gpu.state.depth_test_get(), gpu.state.depth_mask_get()  # the caller's, given back
    with _warm_target.bind():
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        draw_part(part, mode, push_constants(WARM_VIEW, 0.0, drawing.page_heights))
    gpu.state.depth_test_set(test)
    gpu.state.depth_mask_set(mask)
    _warmed.add((*variant, mode))


def release_shader() -> None:
    """Forget the compiled shaders and the warm-up buffer (on unregister: a re-enabled extension compiles its
    own)."""
    global _warm_target
    _shaders.clear()
    _warmed.clear()
    if _warm_target is not None:
        _warm_target.free()
        _warm_target = None


def filtered(texture):
    """`texture` with linear filtering. (Blender versions without GPUTexture.filter_mode sample the nearest texel:
    blockier, the same light.)"""
    if hasattr(texture, "filter_mode"):
        texture.filter_mode(True)
    return texture


def rgba_texture(pixels: np.ndarray):
    """An (H, W, 3|4) float array, rows bottom-up, as an RGBA32F GPUTexture with linear filtering."""
    h, w = pixels.shape[:2]
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :pixels.shape[2]] = pixels[..., :4]
    return filtered(gpu.types.GPUTexture((w, h), format="RGBA32F",
                                         data=gpu.types.Buffer("FLOAT", rgba.size, rgba.ravel())))


def layers_texture(rows: np.ndarray):
    """(L, S, 4) float rows as a 1D array texture of L layers of S texels, RGBA32F, linear filtering: a lookup
    blends two texels of one row, where a 2D texture's blends four."""
    rows = np.ascontiguousarray(rows, np.float32)
    return filtered(gpu.types.GPUTexture(rows.shape[1], layers=rows.shape[0], format="RGBA32F",
                                         data=gpu.types.Buffer("FLOAT", rows.size, rows.ravel())))


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


WARM_VIEW = View(np.eye(4), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0))  # any view: compile_next_shader's warm-up draw


def vertex_buffer(arrays: dict):
    """name → (N, C) float32 arrays as one GPUVertBuf (the shaders find their inputs by name)."""
    fmt = gpu.types.GPUVertFormat()
    for name, a in arrays.items():
        fmt.attr_add(id=name, comp_type="F32", len=a.shape[1], fetch_mode="FLOAT")
    vbo = gpu.types.GPUVertBuf(fmt, len(arrays["pos"]))
    for name, a in arrays.items():
        vbo.attr_fill(id=name, data=a)
    return vbo


class SurfaceDrawing:
    """One GI result on the GPU, ready to be drawn from any view."""

    def __init__(self, light):
        coarse = light.indirect_atlas or light.atlas
        coarse_base = light.base if light.indirect_base is None else light.indirect_base
        self.page_heights = (float(light.atlas.height), float(coarse.height))
        # Both pages of an atlas show the same surfaces' colours.
        atlases = {"u_direct": rgba_texture(light.direct * np.concatenate([light.base, light.base])),
                   "u_indirect": rgba_texture(light.indirect * np.concatenate([coarse_base, coarse_base]))}
        self.triangles = len(light.mesh["pos"]) // 3
        self.parts = []  # ((share, flat), batch, {sampler: texture}), in drawing order
        if not self.triangles:
            return
        rows, layers = share_rows(material_lut_of(light)), gpu.capabilities.max_texture_layers_get()
        coeffs, error = share_polynomial(rows)
        arrays, parts = split_mesh(light.mesh, rows, layers, error <= POLY_TOLERANCE)
        vbo = vertex_buffer(arrays)
        shares = {}  # (sampler, first material) → its table or polynomial texture, made once for all its parts
        for (share, flat), corners, first in parts:
            textures = dict(atlases)
            for sampler, _ in SHARE_SAMPLERS[share]:
                if (sampler, first) not in shares:  # polynomials: a material a row, its channels' 2 texels each
                    shares[sampler, first] = (layers_texture(rows[first:first + layers]) if share == TABLE else
                                              rgba_texture(coeffs[first:first + layers].reshape(-1, 6, 4)))
                textures[sampler] = shares[sampler, first]
            batch = gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=gpu.types.GPUIndexBuf(type="TRIS", seq=corners))
            self.parts.append(((share, flat), batch, textures))
        for variant, mode in cold_variants(self, ("COMBINED",)):  # the default display, before its first redraw:
            warm_variant(self, variant, mode)  # at 1×1 a few ms, at first draw in the view several times that

    def draw(self, view: View, mode: str = "COMBINED", depth_pull: float = 0.0) -> None:
        """Draw into the bound framebuffer, depth-tested (LESS_EQUAL) and depth-writing, both sides of every
        triangle: up to FRONT_FIRST_TRIANGLES those facing the camera first, in every part, then the others (a
        pass with back faces culled, then one with front faces culled: each triangle is drawn once)."""
        if not self.parts:
            return
        constants = push_constants(view, depth_pull, self.page_heights)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        for culled in ("BACK", "FRONT") if self.triangles <= FRONT_FIRST_TRIANGLES else ("NONE",):
            gpu.state.face_culling_set(culled)
            for part in self.parts:
                draw_part(part, mode, constants)
        gpu.state.face_culling_set("NONE")
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)

    def free(self) -> None:
        """Drop the textures and the batches (Blender frees GPU objects when their Python objects go)."""
        self.parts = []


def push_constants(view: View, depth_pull: float, page_heights) -> dict:
    """The surface shader's push constants for `view` (surface.glsl)."""
    return {"u_view_projection": Matrix(np.asarray(view.view_projection, float).tolist()),
            "u_eye": (*view.eye, 1.0 if view.ortho else 0.0), "u_forward": (*view.forward, float(depth_pull)),
            "u_pages": page_heights}


def draw_part(part, mode: str, constants: dict) -> None:
    """Draw one part ((variant, batch, textures) of SurfaceDrawing.parts) in display mode `mode`."""
    variant, batch, textures = part
    shader = surface_shader(*variant, mode)
    shader.bind()
    for name, value in constants.items():
        shader.uniform_float(name, value)
    for name, texture in textures.items():
        shader.uniform_sampler(name, texture)
    batch.draw(shader)


def draw_frame(drawing: SurfaceDrawing | None, view: View, background, mode="COMBINED") -> None:
    """Clear the bound framebuffer to the world colour and draw the surfaces into it: scene-linear values, no view
    transform."""
    fb = gpu.state.active_framebuffer_get()
    fb.clear(color=(*tuple(background)[:3], 1.0), depth=1.0)
    if drawing is not None:
        drawing.draw(view, mode)


def draw_view3d(drawing: SurfaceDrawing | None, view: View, background, mode="COMBINED") -> None:
    """Rendered shading's redraw (render_engine.view_draw), straight into the 3D view's framebuffer that Blender
    binds around view_draw. That buffer is scene-linear — Blender applies the view transform itself, and
    RenderEngine.bind_display_space_shader only binds its plain image shader — so an offscreen and a copy through
    that shader added nothing but time (1.4 ms a redraw at 960 × 540 on llvmpipe). The buffer's depth, which
    Blender cleared to 1 and tests its overlays against (its external engine "only draws color"), is cleared
    back to 1 after the surfaces used it."""
    draw_frame(drawing, view, background, mode)
    if drawing is not None:
        gpu.state.active_framebuffer_get().clear(depth=1.0)


def draw_offscreen(drawing: SurfaceDrawing | None, offscreen, view: View, background, mode="COMBINED") -> None:
    """draw_frame into `offscreen` (`bounce-gi snapshot`)."""
    with offscreen.bind():
        draw_frame(drawing, view, background, mode)


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
