"""GL passes for direct light: geometry upload, material textures, shadow atlas, G-buffer, direct lighting.

Each function takes the moderngl context (and a ProgramCache) plus plain inputs and returns GL objects or numpy;
`pipeline.py` wires them into the cached pass graph.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import camera as cam
from . import light_buffers as lb
from .scene import Scene

GBUFFER_TARGETS = ("position", "normal", "albedo", "emission", "geo_normal", "glossy")


@dataclass
class GeometryBuffers:
    vbo: object
    vao_full: object  # position, normal, uv, geometric normal
    vao_depth: object  # position only (shadow maps)
    ranges: list  # (material index, first vertex, vertex count), triangles grouped by material

    def release(self):
        for obj in (self.vao_full, self.vao_depth, self.vbo):
            obj.release()


def upload_geometry(ctx, programs, scene: Scene) -> GeometryBuffers:
    """Interleave corners (position, normal, uv, geometric normal) grouped by material into one VBO."""
    order = np.argsort(scene.material_index, kind="stable")
    pos = scene.positions[order].astype(np.float32)
    nrm = scene.normals[order].astype(np.float32)
    uvs = scene.uvs[order].astype(np.float32)
    geo = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    geo /= np.maximum(np.linalg.norm(geo, axis=1, keepdims=True), 1e-30)
    geo = np.repeat(geo[:, None, :], 3, axis=1)
    data = np.concatenate([pos, nrm, uvs, geo], axis=2).astype(np.float32)  # (T, 3, 11)
    vbo = ctx.buffer(np.ascontiguousarray(data).tobytes() or b"\0" * 44)
    gbuf = programs.raster("gbuffer.glsl")
    depth = programs.raster("shadow_depth.glsl")
    vao_full = ctx.vertex_array(gbuf, [(vbo, "3f 3f 2f 3f", "in_position", "in_normal", "in_uv", "in_geo_normal")])
    vao_depth = ctx.vertex_array(depth, [(vbo, "3f 32x", "in_position")])
    mats = scene.material_index[order]
    ranges = []
    if len(mats):
        starts = np.flatnonzero(np.r_[True, mats[1:] != mats[:-1]])
        ends = np.r_[starts[1:], len(mats)]
        ranges = [(int(mats[s]), int(s) * 3, int(e - s) * 3) for s, e in zip(starts, ends)]
    return GeometryBuffers(vbo, vao_full, vao_depth, ranges)


def upload_textures(ctx, scene: Scene) -> list:
    """Material textures as float RGBA, bilinear without mipmaps (Cycles' CPU 'Linear' filtering)."""
    import moderngl

    out = []
    for tex in scene.textures:
        px = np.ascontiguousarray(tex.pixels, np.float32)
        h, w = px.shape[:2]
        t = ctx.texture((w, h), 4, px.tobytes(), dtype="f4")
        f = moderngl.NEAREST if tex.interpolation == "Closest" else moderngl.LINEAR
        t.filter = (f, f)
        t.repeat_x = t.repeat_y = tex.extension == "REPEAT"
        out.append(t)
    return out


@dataclass
class ShadowAtlas:
    depth: object  # depth texture with comparison enabled
    size: tuple
    light_ssbo: object
    view_ssbo: object
    polygon_ssbo: object
    light_count: int
    view_count: int
    warnings: list
    buffers: lb.LightBuffers  # the CPU-side records (RSMs reuse the views)

    def release(self):
        for obj in (self.depth, self.light_ssbo, self.view_ssbo, self.polygon_ssbo):
            obj.release()


def render_shadow_atlas(ctx, programs, scene: Scene, geometry: GeometryBuffers,
                        settings: lb.ShadowSettings) -> ShadowAtlas:
    """Render every light's shadow views into one depth atlas and upload the light/view/polygon buffers."""
    import moderngl

    buffers = lb.build_light_buffers(scene, settings)
    max_size = ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384)
    tiles, size, scale = lb.allocate_atlas([v.resolution for v in buffers.views], max_height=max_size)
    warnings = list(buffers.warnings)
    if scale > 1:
        warnings.append(f"shadow maps reduced {scale}x to fit the atlas ({len(buffers.views)} views)")
    depth = ctx.depth_texture(size)
    depth.compare_func = "<="
    depth.filter = (moderngl.LINEAR, moderngl.LINEAR)
    depth.repeat_x = depth.repeat_y = False
    if buffers.views:
        fbo = ctx.framebuffer(depth_attachment=depth)
        fbo.use()
        fbo.clear(depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        prog = programs.raster("shadow_depth.glsl")
        for view, (x, y, w, h) in zip(buffers.views, tiles):
            fbo.viewport = (x, y, w, h)
            prog["u_view_projection"].write(view.view_projection.T.astype("f4").tobytes())
            prog["u_origin"].value = tuple(float(c) for c in view.origin)
            prog["u_far"].value = float(view.far)
            geometry.vao_depth.render(moderngl.TRIANGLES)
        fbo.release()
    views = lb.pack_views(buffers.views, tiles, size, settings.pcf_radius, buffers.view_lights)
    return ShadowAtlas(depth, size, ssbo(ctx, buffers.lights), ssbo(ctx, views), ssbo(ctx, buffers.polygon_vertices),
                       len(buffers.lights), len(buffers.views), warnings, buffers)


def ssbo(ctx, array: np.ndarray):
    data = np.ascontiguousarray(array).tobytes()
    return ctx.buffer(data if data else b"\0" * 16)


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
    prog = programs.raster("gbuffer.glsl")
    cam_world = np.asarray(camera.matrix_world, np.float64)
    forward = -cam_world[:3, 2] / np.linalg.norm(cam_world[:3, 2])
    prog["u_view_projection"].write((proj @ view).T.astype("f4").tobytes())
    set_uniform(prog, "u_camera_position", tuple(cam_world[:3, 3]))
    set_uniform(prog, "u_camera_forward", tuple(forward))
    set_uniform(prog, "u_camera_ortho", camera.type == "ORTHO")
    draw_by_material(prog, scene, geometry, textures)
    return GBuffer(targets, depth, fbo, (width, height), tuple(float(c) for c in cam_world[:3, 3]),
                   tuple(float(c) for c in forward), camera.type == "ORTHO")


def bind_material(prog, scene: Scene, mat_index: int, textures: list) -> None:
    """Set the material uniforms of materials_common.glsl for one material (unused ones are skipped)."""
    mat = scene.materials[mat_index] if 0 <= mat_index < len(scene.materials) else None
    base = mat.base_color if mat else (0.8, 0.8, 0.8)
    set_uniform(prog, "u_base_color", tuple(float(c) for c in base[:3]))
    set_uniform(prog, "u_metallic", float(mat.metallic) if mat else 0.0)
    set_uniform(prog, "u_roughness", float(mat.roughness) if mat else 0.5)
    set_uniform(prog, "u_specular_layer", bool(mat and mat.specular_layer))
    set_uniform(prog, "u_emission", tuple(float(c) for c in (mat.emission if mat else (0, 0, 0))[:3]))
    use_tex = bool(mat and 0 <= mat.base_color_texture < len(textures))
    set_uniform(prog, "u_use_texture", use_tex)
    if use_tex:
        textures[mat.base_color_texture].use(location=0)
        set_uniform(prog, "u_base_texture", 0)


def draw_by_material(prog, scene: Scene, geometry: GeometryBuffers, textures: list, vao=None) -> None:
    """Draw the geometry one material range at a time with that material's uniforms (materials_common.glsl)."""
    import moderngl

    vao = vao or geometry.vao_full
    for mat_index, first, count in geometry.ranges:
        bind_material(prog, scene, mat_index, textures)
        vao.render(moderngl.TRIANGLES, vertices=count, first=first)


def set_uniform(prog, name, value):
    """Set a uniform if the compiler kept it (unused uniforms are optimised away)."""
    if name in prog:
        prog[name].value = value


def render_direct_light(ctx, programs, gbuffer: GBuffer, shadows: ShadowAtlas):
    """Diffuse Direct (irradiance/π) for every G-buffer pixel, as an RGBA32F texture."""
    w, h = gbuffer.size
    out = ctx.texture((w, h), 4, dtype="f4")
    prog = programs.compute("direct_light.glsl")
    out.bind_to_image(0, read=False, write=True)
    for unit, name in enumerate(("position", "normal", "geo_normal")):
        gbuffer.textures[name].use(location=unit)
        set_uniform(prog, f"u_{name}", unit)
    shadows.depth.use(location=3)
    set_uniform(prog, "u_shadow_atlas", 3)
    set_uniform(prog, "u_atlas_texel", (1.0 / shadows.size[0], 1.0 / shadows.size[1]))
    set_uniform(prog, "u_light_count", shadows.light_count)
    set_uniform(prog, "u_size", (w, h))
    shadows.light_ssbo.bind_to_storage_buffer(0)
    shadows.view_ssbo.bind_to_storage_buffer(1)
    shadows.polygon_ssbo.bind_to_storage_buffer(2)
    prog.run((w + 7) // 8, (h + 7) // 8, 1)
    return out


def read_texture(texture, components: int = 4) -> np.ndarray:
    """RGBA32F texture → (H, W, components) float32 with rows top-to-bottom (image order)."""
    w, h = texture.size
    data = np.frombuffer(texture.read(), np.float32).reshape(h, w, 4)
    return np.ascontiguousarray(data[::-1, :, :components])


_set = set_uniform  # short alias used throughout gpu_kernels
