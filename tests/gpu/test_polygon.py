# SPDX-License-Identifier: GPL-3.0-or-later
"""common/polygon.glsl split_octagon_projected_solid_angles — the LPV transfer's near field (lpv/gather.glsl
polygon_kernel) — against a clip-then-Lambert reference in numpy: convex octagons in random planes (and a rectangle
given as an octagon with repeated corners) seen from points on either side of them, with random normals, so the
receiver's plane leaves them whole above, whole below or cuts them into a triangle, quad, pentagon or more."""
import numpy as np
import pytest

PROBE = """
#version 430 core
#include "common/polygon.glsl"
layout(local_size_x = 1) in;
layout(std430, binding = 0) readonly buffer Octagons { vec4 corners[]; };  // per case: 8 corners
layout(std430, binding = 1) readonly buffer Probes { vec4 probes[]; };     // per case: point, normal
layout(std430, binding = 2) writeonly buffer Out { vec2 out_v[]; };
void main() {
    int i = int(gl_GlobalInvocationID.x);
    vec3 p = probes[2 * i].xyz, n = probes[2 * i + 1].xyz;
    vec3 q[8];
    for (int k = 0; k < 8; ++k) q[k] = corners[8 * i + k].xyz - p;
    out_v[i] = split_octagon_projected_solid_angles(q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], n);
}
"""


def _lambert(poly: np.ndarray, n: np.ndarray) -> float:
    """½ |Σ_edges angle(a, b) · n·normalize(a × b)| of a polygon (vertices relative to the receiver)."""
    total = 0.0
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
        c = np.cross(a, b)
        s = np.linalg.norm(c)
        if s > 1e-15:
            total += np.arctan2(s, a @ b) * (n @ c) / s
    return 0.5 * abs(total)


def _clip(poly: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The part of a convex polygon with n·x ≥ 0 (Sutherland–Hodgman)."""
    out = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        ha, hb = a @ n, b @ n
        if ha >= 0:
            out.append(a)
        if (ha >= 0) != (hb >= 0):
            out.append(a + (b - a) * (ha / (ha - hb)))
    return np.array(out)


def _cases(rng, count):
    octagons, probes = [], []
    for i in range(count):
        centre = rng.uniform(-1, 1, 3)
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        t1 = np.cross(normal, rng.normal(size=3))
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(normal, t1)
        if i % 4 == 0:  # a rectangle as lpv/clusters.polygons gives it: corners repeated
            a, b = rng.uniform(0.2, 1.0, 2)
            uv = [(-a, -b), (-a, -b), (a, -b), (a, -b), (a, b), (a, b), (-a, b), (-a, b)]
        else:  # a convex octagon: points on an ellipse, in order
            angles = np.sort(rng.uniform(0, 2 * np.pi, 8))
            a, b = rng.uniform(0.2, 1.0, 2)
            uv = np.stack([a * np.cos(angles), b * np.sin(angles)], axis=1)
        octagons.append(np.array([centre + u * t1 + v * t2 for u, v in uv]))
        point = centre + rng.uniform(-1.2, 1.2, 3)
        point += normal * (0.05 * np.sign(normal @ (point - centre)) or 0.05)  # never in the octagon's plane
        n = rng.normal(size=3)
        probes.append((point, n / np.linalg.norm(n)))
    return np.array(octagons), probes


def _run_probe(tmp_path, source: str, inputs: list, out_floats: int, count: int) -> np.ndarray:
    """Compute shader `source` (it may include the repository's shaders) over `count` invocations, with `inputs` on
    storage buffers 0, 1, … and an output buffer of `out_floats` floats an invocation after them: its (count,
    out_floats) float64 result."""
    moderngl = pytest.importorskip("moderngl")
    from bounce_gi.gpu_kernels.gl import preprocessor as spp

    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception as exc:  # no EGL / GL 4.3 here
        pytest.skip(f"no OpenGL 4.3 context: {exc}")
    src = tmp_path / "probe.glsl"
    src.write_text(source)
    prog = ctx.compute_shader(spp.preprocess(src, search_dirs=[spp.SHADER_DIR]).text)
    bufs = [ctx.buffer(a.tobytes()) for a in inputs] + [ctx.buffer(reserve=count * 4 * out_floats)]
    for i, b in enumerate(bufs):
        b.bind_to_storage_buffer(i)
    prog.run(count, 1, 1)
    out = np.frombuffer(bufs[-1].read(), np.float32).reshape(count, out_floats).astype(np.float64)
    for b in bufs:
        b.release()
    prog.release()
    ctx.release()
    return out


def test_split_octagon_projected_solid_angles_match_clipping_then_lambert(tmp_path):
    count = 256
    octagons, probes = _cases(np.random.default_rng(5), count)
    corners = np.zeros((count, 8, 4), np.float32)
    corners[..., :3] = octagons
    probe = np.zeros((count, 2, 4), np.float32)
    probe[:, 0, :3] = [p for p, _ in probes]
    probe[:, 1, :3] = [n for _, n in probes]
    ours = _run_probe(tmp_path, PROBE, [corners, probe], 2, count)
    exact, kinds = np.zeros((count, 2)), set()
    for i, octagon in enumerate(corners[..., :3].astype(np.float64)):  # the float32 inputs the shader got
        q = octagon - probe[i, 0, :3].astype(np.float64)
        n = probe[i, 1, :3].astype(np.float64)
        above, below = _clip(q, n), _clip(q, -n)
        exact[i] = (_lambert(above, n) if len(above) >= 3 else 0.0, _lambert(below, -n) if len(below) >= 3 else 0.0)
        kinds.add((len(above) >= 3, len(below) >= 3))
    assert kinds == {(True, False), (False, True), (True, True)}  # whole above, whole below, split: all met
    # float32 arithmetic over eight edges' atan terms: a few 1e-5 relative (2e-4 allowed); atol for slivers
    np.testing.assert_allclose(ours, exact, rtol=2e-4, atol=2e-6)


TRIANGLE_PROBE = """
#version 430 core
#include "common/polygon.glsl"
layout(local_size_x = 1) in;
layout(std430, binding = 0) readonly buffer Triangles { vec4 corners[]; };  // per case: 3 corners, the point, n
layout(std430, binding = 1) writeonly buffer Out { vec4 out_v[]; };
void main() {
    int i = int(gl_GlobalInvocationID.x);
    vec3 p = corners[5 * i + 3].xyz, n = corners[5 * i + 4].xyz;
    vec3 a = corners[5 * i].xyz - p, b = corners[5 * i + 1].xyz - p, c = corners[5 * i + 2].xyz - p;
    out_v[i] = vec4(triangle_projected_solid_angles(a, b, c, n),
                    triangle_projected_solid_angle(a, b, c, n), triangle_projected_solid_angle(a, b, c, -n));
}
"""


def test_triangle_projected_solid_angles_are_both_sides_of_one_triangle(tmp_path):
    """triangle_projected_solid_angles (VCT's injection lights both sides of a surface point with it) against the
    clip-then-Lambert reference for n and −n, and against two calls of the one-sided triangle_projected_solid_angle:
    triangles whole above, whole below and cut by the receiver's plane."""
    count = 256
    octagons, probes = _cases(np.random.default_rng(7), count)
    cases = np.zeros((count, 5, 4), np.float32)
    cases[:, :3, :3] = octagons[:, [0, 3, 5]]  # three of a convex octagon's corners: a triangle in its plane
    cases[:, 3, :3] = [p for p, _ in probes]
    cases[:, 4, :3] = [n for _, n in probes]
    ours = _run_probe(tmp_path, TRIANGLE_PROBE, [cases], 4, count)
    exact, kinds = np.zeros((count, 2)), set()
    for i, case in enumerate(cases[..., :3].astype(np.float64)):
        q, n = case[:3] - case[3], case[4]
        above, below = _clip(q, n), _clip(q, -n)
        exact[i] = (_lambert(above, n) if len(above) >= 3 else 0.0, _lambert(below, -n) if len(below) >= 3 else 0.0)
        kinds.add((len(above) >= 3, len(below) >= 3))
    assert kinds == {(True, False), (False, True), (True, True)}
    # float32 over three edges' atan terms (as the octagons' test); the two functions take the same terms
    np.testing.assert_allclose(ours[:, :2], exact, rtol=2e-4, atol=2e-6)
    np.testing.assert_allclose(ours[:, :2], ours[:, 2:], rtol=1e-5, atol=1e-6)
