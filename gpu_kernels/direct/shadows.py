# SPDX-License-Identifier: GPL-3.0-or-later
"""Shadow maps of every light in one depth atlas, with the light, view and polygon records the shaders read
(common/lights.py builds them; direct/eval.glsl reads them)."""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from ..common import atlas
from ..common import lights as lb
from ..gl.bind import dispatch, set_uniform, ssbo, write_uniform
from ..scene import Scene, hash_parts
from .geometry import GeometryBuffers


def emitter_records(lights: np.ndarray) -> np.ndarray:
    """Which of the light records (common/lights.LIGHT_DTYPE) are an emissive mesh's clusters: polygon lights whose
    polygon is a triangle list (polygon.w = 1, lights.triangle_list_vertices), not an area light's outline."""
    return (lights["color_type"][:, 3] == lb.LIGHT_POLYGON) & (lights["polygon"][:, 3] > 0.5)


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
    owns_depth: bool = True  # False where the depth atlas is cached apart (render_shadow_atlas's depth_pass)
    views_key: str = ""  # views_key: what the maps and records are besides the lights' colours
    light_keys: list = None  # light_signatures: the same, per light
    rows: np.ndarray = None  # view_rows of buffers.views: what each view's maps are drawn from
    maps: object = None  # the DepthAtlas `depth` belongs to (its serial, generation and last redraw)
    _raw: object = None

    @property
    def defines(self) -> dict:
        """Defines for a program that evaluates these lights (common/light_eval.glsl): NO_TRIANGLE_LISTS where none
        is an emitter's triangle list (the scene has no emissive mesh), which leaves that code out of the program."""
        return {} if np.any(emitter_records(self.buffers.lights)) else {"NO_TRIANGLE_LISTS": None}

    def raw_depth(self):
        """A sampler reading `depth`'s values without comparison, nearest (made on first use)."""
        import moderngl

        if self._raw is None:
            self._raw = self.depth.ctx.sampler(repeat_x=False, repeat_y=False, filter=(moderngl.NEAREST,
                                               moderngl.NEAREST), compare_func="", texture=self.depth)
        return self._raw

    def release(self):
        for obj in (self.light_ssbo, self.view_ssbo, self.polygon_ssbo) + ((self.depth,) if self.owns_depth else ()):
            obj.release()
        if self._raw is not None:
            self._raw.release()


def render_shadow_atlas(ctx, programs, scene: Scene, geometry: GeometryBuffers,
                        settings: lb.ShadowSettings, trapping: list | None = None, depth_pass=None,
                        static_pass=None) -> ShadowAtlas:
    """Render every light's shadow views into one depth atlas and upload the light/view/polygon buffers.
    `trapping`: the closed emitters whose inner light is trapped (common/emitters.trapping_shells).
    `depth_pass(key, render)`: where the depth atlas is cached apart (the pipeline's 'shadow_depth' pass), keyed by
    `depth_key` of the views; a light's power or colour, or the world's, moves no view, so such an edit renders no
    depth. It calls render(prior), prior a DepthAtlas of the same geometry or None (render_depth). None: rendered
    here, and the atlas owns it. `static_pass(make)`: where the emitters' and the sky's lights are cached apart
    (common/lights.static_lights: a lamp's or the world's edit does not move them); None: made here."""
    def make_static():
        return lb.static_lights(scene, settings, trapping)

    static = make_static() if static_pass is None else static_pass(make_static)
    buffers = lb.build_light_buffers(scene, settings, trapping, static)
    max_size = ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384)
    tiles, size, scale = atlas.allocate_atlas([v.resolution for v in buffers.views], max_height=max_size)
    warnings = list(buffers.warnings)
    if scale > 1:
        warnings.append(f"shadow maps reduced {scale}x to fit the atlas ({len(buffers.views)} views)")

    rows = view_rows(buffers.views)

    def render(prior=None):
        return render_depth(ctx, programs, geometry, buffers.views, tiles, size, prior, rows, scene.positions)

    key = depth_key(rows, tiles, size)
    maps = render() if depth_pass is None else depth_pass(key, render)
    views = atlas.pack_views(buffers.views, tiles, size, settings.pcf_radius, buffers.view_lights)
    return ShadowAtlas(maps.texture, size, ssbo(ctx, buffers.lights), ssbo(ctx, views),
                       ssbo(ctx, buffers.polygon_vertices), len(buffers.lights), len(buffers.views), warnings, buffers,
                       owns_depth=depth_pass is None, views_key=views_key(buffers, key, views),
                       light_keys=light_signatures(buffers, views), rows=rows, maps=maps)


def light_signatures(buffers: lb.LightBuffers, packed: np.ndarray) -> list:
    """Per light, a key of what its shadow maps and its light are made from besides its colour (and the geometry):
    its record (colour left out), its polygon and its views as packed (atlas.pack_views: projection, tile, texel
    size, PCF radius). An edit that leaves a light's key leaves whatever was made from that light alone: its
    Diffuse Direct (direct/lighting.py), the sky's visibility (direct/sky.py), its first bounce (lpv/passes.py)."""
    owner = np.asarray(buffers.view_lights or [], np.int64)
    out = []
    for i, rec in enumerate(buffers.lights):
        rec = rec.copy()
        rec["color_type"][:3] = 0.0
        first, count = int(rec["polygon"][0]), int(rec["polygon"][1])
        out.append(hash_parts(rec, buffers.polygon_vertices[first:first + count], packed[owner == i]))
    return out


def sky_key(shadows: ShadowAtlas) -> tuple:
    """The sky lights' keys (light_signatures): what the sky's visibility is made from besides the G-buffer."""
    kinds = shadows.buffers.lights["color_type"][:, 3] if len(shadows.buffers.lights) else []
    return tuple(k for k, kind in zip(shadows.light_keys, kinds) if int(kind) == lb.LIGHT_SKY)


def views_key(buffers: lb.LightBuffers, depth: str, packed) -> str:
    """What the shadow maps and every light record are besides the lights' colours (colour × power or strength):
    the depth atlas's key, the packed views, the records with their colours zeroed, the polygons. Whatever depends
    on the lights' shapes and places but scales with their colours (the sky's visibility, the RSMs) is keyed by
    it, so a colour, power or world edit leaves it."""
    records = buffers.lights.copy()
    records["color_type"][:, :3] = 0.0
    return hash_parts(depth, packed, records, buffers.polygon_vertices)


def depth_key(rows: np.ndarray, tiles: list, size: tuple) -> str:
    """What the depth atlas is drawn from besides the geometry: each view's projection, eye and depth range
    (view_rows), and where its tile lies."""
    return hash_parts(rows, np.asarray(tiles, np.int64).reshape(-1, 4), tuple(size))


@dataclass
class DepthAtlas:
    """The depth atlas (comparison enabled) and what each of its tiles holds: `views` (N, 20) rows of a view's
    projection, eye and depth range (view_rows). A later atlas of the same geometry whose views fill the same tiles
    redraws only the tiles whose view changed: a light's move redraws that light's maps, not every light's."""
    texture: object
    tiles: list
    size: tuple
    views: np.ndarray
    drawn: int = 0  # views drawn (whole or in part) when it was last made or updated
    drawn_from: np.ndarray = None  # the scene's triangles it was drawn from (Scene.positions)
    partial: int = 0  # of the views drawn, those drawn in a rectangle only (an object's move: moved_rects)
    # Which atlas this is and how many updates it has had; `redrawn`: the last update's (view, rect) pairs (rect
    # (x, y, w, h) in atlas texels, None for the whole tile), None when it was drawn whole. What was lit from the
    # atlas one update ago may keep its pixels that read none of those texels (direct/lighting.Relight).
    serial: int = field(default_factory=itertools.count().__next__)
    generation: int = 0
    redrawn: list = None
    overwritten: KeptTexels = None  # the depths the last update's rectangles overwrote, and which of them changed

    def release(self):
        self.texture.release()
        if self.overwritten is not None:
            self.overwritten.release()


@dataclass
class KeptTexels:
    """Depths an update of the atlas overwrote (keep_texels): per view index, (x, y, w, h, first) — its redrawn
    rectangle in atlas texels and where its texels start in `buffer` (float32, row by row); `changed` per view the
    box (x0, y0, x1, y1) of the texels the update changed in it, None where it changed none (find_changed)."""
    buffer: object
    rects: dict
    table: object = None  # the rectangles on the GPU (keep_texels.glsl Rects)
    changed: dict = None

    def release(self):
        self.buffer.release()
        if self.table is not None:
            self.table.release()


# The most texels an update keeps (16 MiB, one dispatch of groups of 64; the example scenes' object moves keep
# 0.05-2.9 M): a move whose rectangles hold more keeps none, and what reads them is lit again as if every texel of
# the rectangles had changed.
MAX_KEPT_TEXELS = 65535 * 64


def keep_texels(ctx, programs, depth, rects: list) -> KeptTexels | None:
    """The depths of `depth` inside `rects` ((view, (x, y, w, h)) pairs), copied before they are drawn over
    (direct/keep_texels.glsl); None where there are none or more than MAX_KEPT_TEXELS."""
    total = sum(w * h for _, (_, _, w, h) in rects)
    if not rects or total > MAX_KEPT_TEXELS:
        return None
    firsts = np.concatenate([[0], np.cumsum([w * h for _, (_, _, w, h) in rects])[:-1]]).astype(np.int64)
    table = ssbo(ctx, np.array([(x, y, w, h, int(f), 0, 0, 0) for (_, (x, y, w, h)), f in zip(rects, firsts)],
                               np.int32))
    out = ctx.buffer(reserve=4 * total)
    _run_over_rects(ctx, programs, depth, rects, table, out, None)
    return KeptTexels(out, {v: (x, y, w, h, int(f)) for (v, (x, y, w, h)), f in zip(rects, firsts)}, table)


def find_changed(ctx, programs, depth, kept: KeptTexels) -> None:
    """kept.changed: per view the box of the texels whose depth the draws changed, compared with the kept ones
    (keep_texels.glsl MODE_CHANGED). A small object's move in a large scene changes few of the texels its box's
    rectangles hold (the rectangles grow by MOVED_MARGIN texels, and its own texels are coarse)."""
    rects = [(v, r[:4]) for v, r in kept.rects.items()]
    start = np.tile(np.array([1 << 30, 1 << 30, -1, -1], np.int32), len(rects))
    boxes = ctx.buffer(start.tobytes())
    _run_over_rects(ctx, programs, depth, rects, kept.table, kept.buffer, boxes)
    found = np.frombuffer(boxes.read(), np.int32).reshape(-1, 4)
    boxes.release()
    kept.changed = {v: tuple(int(c) for c in box) if box[2] > box[0] else None for (v, _), box in zip(rects, found)}


def _run_over_rects(ctx, programs, depth, rects: list, table, texels, changed) -> None:
    """keep_texels.glsl over every texel of `rects`: copy them into `texels`, or (`changed` given) compare."""
    import moderngl

    raw = ctx.sampler(repeat_x=False, repeat_y=False, filter=(moderngl.NEAREST, moderngl.NEAREST), compare_func="",
                      texture=depth)
    prog = programs.compute("direct/keep_texels.glsl", None if changed is None else {"MODE_CHANGED": None})
    raw.use(location=0)
    set_uniform(prog, "u_depth", 0)
    table.bind_to_storage_buffer(0)
    texels.bind_to_storage_buffer(1)
    if changed is not None:
        changed.bind_to_storage_buffer(2)
    total = sum(w * h for _, (_, _, w, h) in rects)
    set_uniform(prog, "u_rects", len(rects))
    set_uniform(prog, "u_total", total)
    dispatch(prog, (total,), local=64)
    ctx.memory_barrier()
    raw.release()


def view_rows(views: list) -> np.ndarray:
    """(N, 20) float64: each view's projection, eye and depth range — what its depth tile is drawn from."""
    return np.array([np.concatenate([np.ravel(v.view_projection), np.ravel(v.origin), [v.far]]) for v in views],
                    np.float64).reshape(len(views), 20)


def redraw_plan(prior, views: list, tiles: list, size: tuple, rows: np.ndarray, positions):
    """What to draw again into `prior` (a DepthAtlas or an RSM, with .tiles, .size, .views and .drawn_from) for
    `views` in `tiles` of an atlas of `size`: (i, rect) per view — rect None for the whole tile, where the view's
    rows (view_rows) changed; else, where the scene's triangles (`positions`, or a tuple of them and what else the
    atlas holds of each triangle: moved_box) changed since `prior` was drawn, the rectangle they can cover
    (moved_rects). None where `prior` cannot be updated (none, tiled otherwise, another triangle count): draw
    everything."""
    if prior is None or prior.tiles != tiles or prior.size != size:
        return None
    box = None if positions is None else moved_box(prior.drawn_from, positions)
    if box is False:
        return None
    whole = np.any(rows != prior.views, axis=1)
    plan = [(int(i), None) for i in np.nonzero(whole)[0]]
    if box is not None:
        rest = np.nonzero(~whole)[0]
        rects = moved_rects([views[i] for i in rest], box, [tiles[i] for i in rest])
        plan += [(int(i), rect) for i, rect in zip(rest, rects) if rect is not None]
    return plan


def render_depth(ctx, programs, geometry: GeometryBuffers, views: list, tiles: list, size: tuple,
                 prior: DepthAtlas | None = None, rows: np.ndarray | None = None,
                 positions: np.ndarray | None = None) -> DepthAtlas:
    """The depth atlas: every view drawn into its tile (direct/shadow_depth.glsl). With `prior` (an atlas tiled
    alike) only what changed is drawn again, into `prior`, which is returned updated: whoever held it sees the new
    maps (the pass cache, whose entry it then is) — the tiles whose view changed (a light's move redraws that light's
    maps), and where the scene's triangles (`positions`) moved since `prior` was drawn, in every other tile the
    rectangle the moved triangles' box covers (moved_rects). `rows`: view_rows(views). The depths the rectangles
    overwrite are kept, and which of them changed found (DepthAtlas.overwritten, changed_views): what reads none of
    the changed texels keeps its light (direct/lighting.Relight) and its sky shares (direct/sky.py)."""
    import moderngl

    rows = view_rows(views) if rows is None else rows
    tiles, size = [tuple(t) for t in tiles], tuple(size)
    plan = redraw_plan(prior, views, tiles, size, rows, positions)
    if plan is not None:
        depth = prior.texture
    else:
        depth = ctx.depth_texture(size)
        depth.compare_func = "<="
        depth.filter = (moderngl.LINEAR, moderngl.LINEAR)
        depth.repeat_x = depth.repeat_y = False
    draws = [(i, None) for i in range(len(views))] if plan is None else plan
    if plan is not None:
        if prior.overwritten is not None:
            prior.overwritten.release()
        prior.overwritten = keep_texels(ctx, programs, depth, [(i, r) for i, r in draws if r is not None])
    if draws:
        fbo = ctx.framebuffer(depth_attachment=depth)
        fbo.use()
        if plan is None:
            fbo.clear(depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        prog = programs.raster("direct/shadow_depth.glsl")
        for i, rect in draws:
            view, tile = views[i], tiles[i]
            if plan is not None:
                fbo.clear(depth=1.0, viewport=rect or tile)
            if view.unlit:  # behind its light (lights.cube_views): cleared, never read
                continue
            fbo.viewport = tile
            ctx.scissor = rect  # None: the whole tile
            write_uniform(prog, "u_view_projection", view.view_projection.T)
            set_uniform(prog, "u_origin", tuple(float(c) for c in view.origin))
            set_uniform(prog, "u_far", float(view.far))
            geometry.vao_depth.render(moderngl.TRIANGLES)
        ctx.scissor = None
        fbo.release()
    if plan is not None and prior.overwritten is not None:
        find_changed(ctx, programs, depth, prior.overwritten)
    partial = sum(rect is not None for _, rect in draws)
    if plan is not None:
        prior.views, prior.drawn, prior.drawn_from, prior.partial = rows, len(draws), positions, partial
        prior.generation, prior.redrawn = prior.generation + 1, draws
        return prior
    return DepthAtlas(depth, tiles, size, rows, len(draws), positions)


def changed_views(maps: DepthAtlas) -> list:
    """maps.redrawn with each rectangle cut to the box of the texels its redraw changed where they were compared
    (KeptTexels.changed), and the views whose redraw changed none left out: a test that reads none of them gives
    what it gave before."""
    kept = maps.overwritten
    changed = kept.changed if kept is not None and kept.changed is not None else {}
    out = []
    for view, rect in maps.redrawn:
        if rect is None or view not in changed:
            out.append((view, rect))
        elif changed[view] is not None:
            x0, y0, x1, y1 = changed[view]
            out.append((view, (x0, y0, x1 - x0, y1 - y0)))
    return out


def moved_box(before, after):
    """The world box (2, 3) of the triangles that differ between two (T, 3, 3) position arrays, before and after;
    None where none does; False where they cannot be compared (another triangle count, or no record). Either may be
    a tuple of the positions and other per-triangle arrays (normals, UVs, material indices) whose change counts too:
    an RSM holds each texel's normal, texture colour and material, so a material given to an object changes it."""
    before, after = (x if isinstance(x, tuple) else (x,) for x in (before, after))
    if before[0] is None or len(before) != len(after) or any(a.shape != b.shape for a, b in zip(before, after)):
        return False
    changed = np.zeros(len(after[0]), bool)
    for a, b in zip(before, after):
        if a is not b:
            changed |= np.any((a != b).reshape(len(b), -1), axis=1)
    if not changed.any():
        return None
    corners = np.concatenate([before[0][changed], after[0][changed]]).reshape(-1, 3).astype(np.float64)
    return np.stack([corners.min(axis=0), corners.max(axis=0)])


MOVED_MARGIN = 2  # texels around a moved box's projection (rasterisation rules at its edges; depth slope)


# The twelve edges of a box whose corners are numbered i·4 + j·2 + k (x, y, z picked by bits i, j, k).
BOX_EDGES = np.array([(c, c | bit) for bit in (1, 2, 4) for c in range(8) if not c & bit])


def moved_rects(views: list, box: np.ndarray, tiles: list) -> list:
    """Per view of `views`, the rectangle (x, y, w, h) of its tile in `tiles` that the world `box` can cover (grown
    by MOVED_MARGIN texels, within the tile), None where it covers none: the only texels a triangle inside the box
    can write. The box is clipped to the view's near plane first (the rasteriser clips the triangles there), so a
    box reaching behind a cube face's eye covers only what lies in front of it, not the whole tile. All views at
    once: an object's move in a sky-lit room tests its box against the sky's 576 views twice (the depth atlas and
    the RSM), which one view at a time cost 0.4 s."""
    if not views:
        return []
    return box_rects(np.stack([np.asarray(v.view_projection, np.float64) for v in views]), box, tiles)


def box_rects(view_projections: np.ndarray, box: np.ndarray, tiles: list) -> list:
    """moved_rects for (V, 4, 4) world → clip matrices (the G-buffer's camera too: gbuffer.box_pixels)."""
    corners = np.array([[box[i][0], box[j][1], box[k][2], 1.0] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    clip = np.einsum("ck,vjk->vcj", corners, np.asarray(view_projections, np.float64))
    inside = clip[..., 2] + clip[..., 3]  # ≥ 0 in front of the near plane (z ≥ −w)
    a, b = BOX_EDGES[:, 0], BOX_EDGES[:, 1]
    da, db = inside[:, a], inside[:, b]
    crosses = (da >= 0) != (db >= 0)
    t = np.where(crosses, da / np.where(crosses, da - db, 1.0), 0.0)[..., None]
    points = np.concatenate([clip, clip[:, a] + (clip[:, b] - clip[:, a]) * t], axis=1)
    valid = np.concatenate([inside >= 0, crosses], axis=1) & (points[..., 3] > 0)
    ndc = points[..., :2] / np.where(valid, points[..., 3], 1.0)[..., None]
    low = np.where(valid[..., None], ndc, np.inf).min(axis=1)
    high = np.where(valid[..., None], ndc, -np.inf).max(axis=1)
    t = np.asarray(tiles, np.float64)
    with np.errstate(invalid="ignore"):
        lo = np.maximum(np.floor(t[:, :2] + (low * 0.5 + 0.5) * t[:, 2:]) - MOVED_MARGIN, t[:, :2])
        hi = np.minimum(np.ceil(t[:, :2] + (high * 0.5 + 0.5) * t[:, 2:]) + MOVED_MARGIN, t[:, :2] + t[:, 2:])
    return [None if not v.any() or np.any(h <= l) else (int(l[0]), int(l[1]), int(h[0] - l[0]), int(h[1] - l[1]))
            for v, l, h in zip(valid, lo, hi)]
