# SPDX-License-Identifier: GPL-3.0-or-later
"""Emissive meshes (issue 17), on the surface atlas's texels against exact oracles:
(a) a closed emissive shade lights a floor from its outer side only, exactly as much as the triangles facing each
    point send (emission is two-sided, but a closed shell's inner side is hidden from outside: it emits outwards
    only, common/emitters.py);
(b) a closed non-emissive box around the shade lets no light out: every emissive triangle is shadowed;
(c) the light a closed shade emits inwards stays there in the indirect methods too: a white shade (albedo 0.8) and a
    black one inject the same flux into VCT's voxels and give the floor the same indirect light (LPV, VCT); with the
    camera inside the shade, that light is what it sees, and VCT injects it.
"""
import math

import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.scene import Camera, Material, Scene
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.surface.gbuffer import surface_points
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from bounce_gi.tests.support.synthetic import box_quads, closed_cylinder, quad, triangle_projected_solid_angles

BUDGET = 20000
LE = 3.0  # the shade's radiance
CENTRE = np.array([0.0, 0.0, 1.2])


@pytest.fixture(scope="module")
def engine():
    e = Engine()
    yield e
    e.shutdown()


def shade_scene(shade_albedo=0.0, container=False, eye=(2.5, -2.5, 1.6)):
    """A 6 × 6 m white floor at z = 0 and the closed 92-triangle shade (radius 0.22 m, 0.32 m tall) at 1.2 m,
    optionally inside a closed grey box; the camera at `eye`."""
    shade = closed_cylinder(centre=CENTRE)
    parts = [(quad([(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1)), 0), (shade, 1)]
    mats = [Material("floor", (0.8, 0.8, 0.8)), Material("shade", (shade_albedo,) * 3, emission=(LE,) * 3)]
    if container:
        parts += box_quads(CENTRE - 0.4, CENTRE + 0.4, 2, inward=False)
        mats.append(Material("box", (0.5, 0.5, 0.5)))
    pos = np.concatenate([p for p, _ in parts]).astype(np.float32)
    n = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    n = np.repeat((n / np.linalg.norm(n, axis=1, keepdims=True))[:, None], 3, axis=1).astype(np.float32)
    index = np.concatenate([np.full(len(p), m, np.int32) for p, m in parts])
    c2w = np.linalg.inv(cam.look_at(eye, CENTRE * [1, 1, 0.5], (0, 0, 1)))
    return Scene(pos, n, np.zeros((len(pos), 3, 2), np.float32), index, mats, camera=Camera(c2w, lens=20.0))


def floor_texels(scene, r, atlas=None):
    atlas = atlas or r.atlas
    points = surface_points(scene, atlas)
    ys, xs = np.nonzero(np.isin(atlas.triangle, [0, 1]))
    return ys, xs, points["position"][ys, xs].astype(np.float64)


def test_a_closed_shade_lights_the_floor_from_its_outer_side_only(engine):
    scene = shade_scene()
    r = engine.submit_surface(scene, RenderSettings("none", 64, 64), BUDGET).result()
    ys, xs, p = floor_texels(scene, r)
    keep = np.arange(0, len(p), 7)
    ys, xs, p = ys[keep], xs[keep], p[keep]
    shade = closed_cylinder(centre=CENTRE).astype(np.float64)
    psa = triangle_projected_solid_angles(p, np.tile([0.0, 0.0, 1.0], (len(p), 1)), shade)
    cross = np.cross(shade[:, 1] - shade[:, 0], shade[:, 2] - shade[:, 0])
    facing = ((p[:, None] - shade.mean(axis=1)[None]) * cross[None]).sum(-1) > 0  # outer side towards the point
    exact = LE * (psa * facing).sum(1) / math.pi
    both_sides = LE * psa.sum(1) / math.pi  # what an unshadowed two-sided shade would give
    ours = r.direct[ys, xs, 0].astype(np.float64)
    ratio, rel_l1 = ours.sum() / exact.sum(), np.abs(ours - exact).sum() / exact.sum()
    print(f"floor under a closed shade: Σ ours / Σ exact {ratio:.4f}, rel-L1 {rel_l1:.4f}; unshadowed two-sided "
          f"would be {both_sides.sum() / exact.sum():.3f}×; {len(p)} texels")
    assert len(p) > 200 and both_sides.sum() > 1.5 * exact.sum()  # the inner sides matter: the test can fail
    # The exact integral per triangle, the shadows from 1–8 sample points on the outer side of each cluster (measured:
    # ratio 1.0000, rel-L1 below 0.0001; 1.0000 and 0.0050 while the shade was lit two-sided and its inner samples'
    # weights took the inner sides out again; before issue 17, with the brightest 16 triangles shadowed, 1.72, 0.72).
    assert ratio == pytest.approx(1.0, abs=0.02)
    assert rel_l1 < 0.002


def test_a_closed_box_around_the_shade_lets_no_light_out(engine):
    open_ = engine.submit_surface(shade_scene(), RenderSettings("none", 64, 64), BUDGET).result()
    scene = shade_scene(container=True)
    r = engine.submit_surface(scene, RenderSettings("none", 64, 64), BUDGET).result()
    ys, xs, p = floor_texels(scene, r)
    lit = open_.direct[floor_texels(shade_scene(), open_)[:2]][:, 0]
    ours = r.direct[ys, xs, 0]
    print(f"floor outside a closed box around the shade: mean {ours.mean():.3g}, max {ours.max():.3g}, "
          f"{(ours > 0).sum()} of {len(ours)} texels lit (without the box: mean {lit.mean():.3g})")
    # Measured: every texel exactly 0 (4 of 16562 got 1.7% of the unboxed mean while the shade's inner samples were
    # weighted too). Shadowing only the brightest 16 of the 92 triangles (before issue 17) lit every texel, at 83%
    # of the unboxed mean; lighting the outer side unshadowed where no sample faces a receiver lit 5046 of them.
    assert ours.mean() <= 1e-4 * lit.mean()
    assert ours.max() <= 0.05 * lit.mean()


def _floor_indirect(engine, scene, method):
    settings = RenderSettings(method, 64, 64, vct=VctSettings(resolution=32, bounces=1))
    r = engine.submit_surface(scene, settings, BUDGET).result()
    ys, xs, _ = floor_texels(scene, r, r.indirect_atlas)
    return r, float(r.indirect[ys, xs, 0].mean())


@pytest.mark.parametrize("method", ["vct", "lpv"])
def test_the_light_a_closed_shade_emits_inwards_stays_inside(engine, method):
    """The white shade's outer side gets no direct light (convex, lit by nothing else), so what it adds to the black
    shade's result is its outer side reflecting the floor's light (LPV's propagation bounces it), and voxel faces
    VCT lights at their centre for want of raster samples (vct/inject.glsl), which see the shade from just outside
    it. With the camera inside the shade its inner light is what the camera sees and is kept: that is how much the
    inner light adds when it is not left out."""
    black_r, black = _floor_indirect(engine, shade_scene(0.0), method)
    white_r, white = _floor_indirect(engine, shade_scene(0.8), method)
    inside_r, inside = _floor_indirect(engine, shade_scene(0.8, eye=CENTRE + [0.05, 0.0, 0.0]), method)
    share = (white - black) / (inside - black)
    print(f"{method}: floor's Diffuse Indirect, black shade {black:.5f}, white {white:.5f}, white with its inner light "
          f"kept {inside:.5f}: the white shade adds {share:.3f} of what its inner light would")
    assert inside > black + 0.2 * abs(black) + 1e-4  # the inner light would leak out: the test can fail
    # Measured 0.044 (VCT) and 0.015 (LPV; 0.10 while RSM texels on the shade itself were lit by it, light_eval.glsl
    # SELF_PLANE; before issue 17 both 1.0: nothing was left out).
    assert share < (0.15 if method == "vct" else 0.05)
    if method == "vct":  # the direct light injected into the voxels (VCT's first bounce)
        fb, fw, fi = (x.info["bounces"][0]["flux"][0] for x in (black_r, white_r, inside_r))
        print(f"vct injected flux: black {fb:.4f} W, white {fw:.4f} W, white with its inner light kept {fi:.4f} W")
        assert fi > 2 * fb
        assert fw - fb < 0.08 * (fi - fb)  # measured 0.048 (the voxel faces lit at their centre)


# --------------------------------------------------------------------------- the triangle-list polygon light

PSA_PROBE = """
#version 430 core
#include "common/lights.glsl"
#include "common/light_eval.glsl"
layout(local_size_x = 1) in;
layout(std430, binding = 3) readonly buffer Probe { vec4 probe[]; };   // per probe: point, normal
layout(std430, binding = 4) writeonly buffer Out { vec4 out_v[]; };
void main() {
    int i = int(gl_GlobalInvocationID.x);
    vec3 p = probe[2 * i].xyz, n = probe[2 * i + 1].xyz;
    GpuLight L = lights[0];
    vec3 list = polygon_light_solid_angle(L, p, n);
    vec3 by_triangle = vec3(0.0), as_polygons = vec3(0.0);
    for (int t = 0; t < polygon_triangle_count(L); ++t) {
        vec3 a, b, c;
        vec4 scale;
        polygon_triangle(L, t, a, b, c, scale);
        by_triangle += scale.rgb * triangle_projected_solid_angle(a - p, b - p, c - p, n);
        // the same triangle as a 3-vertex polygon (lights[1 + t]) through the general clipper
        as_polygons += scale.rgb * polygon_projected_solid_angle(int(lights[1 + t].polygon.x), 3, p, n);
    }
    out_v[3 * i] = vec4(list, 0.0);
    out_v[3 * i + 1] = vec4(by_triangle, 0.0);
    out_v[3 * i + 2] = vec4(as_polygons, 0.0);
}
"""


def test_a_triangle_list_light_integrates_like_its_triangles_as_polygons(tmp_path):
    """polygon_light_solid_angle of an emitter cluster = Σ radiance scale × the general polygon clipper's result per
    triangle, at points that see the triangles whole, clipped by their horizon, edge-on or from behind."""
    moderngl = pytest.importorskip("moderngl")
    from bounce_gi.gpu_kernels.common import lights as lb
    from bounce_gi.gpu_kernels.gl import preprocessor as spp

    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception as exc:  # no EGL / GL 4.3 here
        pytest.skip(f"no OpenGL 4.3 context: {exc}")
    rng = np.random.default_rng(17)
    tris = rng.uniform(-1, 1, (5, 3, 3))
    scale = rng.uniform(0.1, 1.0, (5, 3))
    rows = lb.triangle_list_vertices(tris, scale, np.ones(3))
    poly = np.concatenate([rows] + [np.concatenate([t, np.ones((3, 1))], axis=1) for t in tris]).astype(np.float32)
    lights = np.zeros(1 + len(tris), lb.LIGHT_DTYPE)
    lights[0]["polygon"] = (0, len(rows), 1, 1)
    for t in range(len(tris)):
        lights[1 + t]["polygon"] = (len(rows) + 3 * t, 3, 1, 0)
    points = rng.uniform(-1.5, 1.5, (64, 3))
    normals = rng.normal(size=(64, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    probe = np.zeros((64, 2, 4), np.float32)
    probe[:, 0, :3], probe[:, 1, :3] = points, normals
    src = tmp_path / "probe.glsl"
    src.write_text(PSA_PROBE)
    prog = ctx.compute_shader(spp.preprocess(src, search_dirs=[spp.SHADER_DIR]).text)
    bufs = [ctx.buffer(lights.tobytes()), ctx.buffer(np.zeros(1, lb.VIEW_DTYPE).tobytes()),
            ctx.buffer(poly.tobytes()), ctx.buffer(probe.tobytes()), ctx.buffer(reserve=64 * 3 * 16)]
    for i, b in enumerate(bufs):
        b.bind_to_storage_buffer(i)
    prog.run(64, 1, 1)
    out = np.frombuffer(bufs[4].read(), np.float32).reshape(64, 3, 4)[..., :3]
    for b in bufs:
        b.release()
    prog.release()
    ctx.release()
    assert out[:, 2].max() > 0.1 and (out[:, 2] == 0).any()  # some see the light, some not at all
    # A point within 1e-2 of a triangle's size of its plane (and over it) lies on it (light_eval.glsl SELF_PLANE):
    # the list may leave that triangle out. The other points must match exactly.
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    length = np.linalg.norm(normal, axis=1)
    height = ((points[:, None] - tris[None, :, 0]) * normal[None]).sum(-1) / length[None]
    on_plane = np.abs(height) <= 1e-2 * np.sqrt(0.5 * length)[None]
    assert 0 < on_plane.any(axis=1).sum() < 8  # the seed puts a few points there: the rule is exercised
    print(f"{on_plane.any(axis=1).sum()} of 64 points lie on a triangle's plane")
    keep = ~on_plane.any(axis=1)
    assert np.all(out[~keep, 0] <= out[~keep, 1] + 1e-6)  # the list leaves the triangle out, nothing else
    np.testing.assert_allclose(out[keep, 0], out[keep, 1], rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(out[:, 1], out[:, 2], rtol=2e-4, atol=1e-6)


def test_an_emissive_quad_lights_like_the_area_light_it_equals(engine):
    """A 0.5 m emissive quad of radiance P/(π·A) and a 300 W square area light in its place light a rough Principled
    floor alike: Diffuse Direct (both exact polygon integrals; shadow samples differ) and Glossy Direct, which reads
    the quad's cluster as a triangle list (direct/ggx.glsl: polygon_glossy through polygon_triangle). Measured:
    Diffuse 0.999 / rel-L1 0.005; Glossy 0.988 / 0.051 — the lobe's quadrature differs (the area light's fan gets
    3² sub-triangles per triangle, each one-triangle cluster 4²)."""
    from bounce_gi.gpu_kernels.scene import Light

    c, s = math.cos(math.radians(20)), math.sin(math.radians(20))
    m = np.eye(4)
    m[:3, :3] = [[1, 0, 0], [0, c, -s], [0, s, c]]
    m[:3, 3] = (0, 1.5, 1.2)
    corners = [m[:3, :3] @ np.array(p) + m[:3, 3] for p in ((-0.25, -0.25, 0), (0.25, -0.25, 0), (0.25, 0.25, 0),
                                                              (-0.25, 0.25, 0))]
    floor = quad([(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1))
    c2w = np.linalg.inv(cam.look_at((0.0, -4.0, 1.5), (0.0, 0.5, 0.0), (0, 0, 1)))
    floor_mat = Material("floor", (0.8,) * 3, roughness=0.5, specular_layer=True)

    def scene(parts, mats, lights):
        pos = np.concatenate(parts).astype(np.float32)
        n = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
        n = np.repeat((n / np.linalg.norm(n, axis=1, keepdims=True))[:, None], 3, axis=1).astype(np.float32)
        index = np.concatenate([np.full(len(p), i, np.int32) for i, p in enumerate(parts)])
        return Scene(pos, n, np.zeros((len(pos), 3, 2), np.float32), index, mats, lights=lights,
                     camera=Camera(c2w, lens=35.0))

    area = scene([floor], [floor_mat], [Light("a", "AREA", (1, 1, 1), 300.0, m, shape="SQUARE", size=0.5)])
    panel = scene([floor, quad(corners, m[:3, :3] @ np.array([0, 0, -1.0]))],
                  [floor_mat, Material("e", (0, 0, 0), emission=(300 / (math.pi * 0.25),) * 3)], [])
    ra, rb = (engine.submit_render(x, RenderSettings("none", 160, 120)).result() for x in (area, panel))
    on_floor = (ra.passes["Position"][..., 2] < 0.01) & (ra.passes["Depth"][..., 0] < 1e9)
    for name, ratio_tol, l1 in (("Diffuse Direct", 0.005, 0.01), ("Glossy Direct", 0.03, 0.08)):
        a, b = ra.passes[name][on_floor][..., :3], rb.passes[name][on_floor][..., :3]
        print(f"{name}: emissive quad / area light {b.sum() / a.sum():.4f}, rel-L1 {np.abs(a - b).sum() / a.sum():.4f}")
        assert b.sum() / a.sum() == pytest.approx(1.0, abs=ratio_tol)
        assert np.abs(a - b).sum() / a.sum() < l1
