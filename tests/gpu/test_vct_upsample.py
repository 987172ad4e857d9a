# SPDX-License-Identifier: GPL-3.0-or-later
"""Reduced-resolution VCT gather and its discontinuity-aware upsampling (inferred lighting, Kircher and Lawrance 2009).

The upsampler (vct/upsample.glsl) is driven directly with fields we choose, on G-buffers rendered from an orthographic
camera looking straight down, where world position is affine in the pixel coordinates, so bilinear interpolation of
a field affine in position is exact:
  (a) constant and affine fields come back exactly (float32 rounding);
  (b) a plate 1 m above a floor, each with its own value: no pixel takes the other surface's value — every pixel
      either gets its own surface's value or is marked for a full-resolution trace;
then (c) the whole pipeline at indirect_scale 2 and 4 stays close to scale 1.
"""
import numpy as np
import pytest

from bounce_gi.gpu_kernels.common import camera as cam
from bounce_gi.gpu_kernels.vct import upsample as vct_upsample
from bounce_gi.gpu_kernels.engine import Engine
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.gpu_kernels.scene import Camera, Material
from bounce_gi.gpu_kernels.vct.settings import VctSettings
from support.synthetic import quad, quad_scene
from test_vct import _sunlit_room

W, H = 64, 48
SIGMA = 0.0625  # plane-distance scale (m): half a voxel of a 32³ grid over 4 m


@pytest.fixture(scope="module")
def engine():
    return Engine()


def _top_view(with_plate: bool):
    quads = [(quad([(-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)], (0, 0, 1)), 0)]
    if with_plate:
        quads.append((quad([(-0.6, -0.5, 1), (0.6, -0.5, 1), (0.6, 0.5, 1), (-0.6, 0.5, 1)], (0, 0, 1)), 0))
        # Two strips 8 cm (1.3 px) wide at the plate's height: thinner than the sample spacing, so some of their
        # pixels have no sample on their surface and must be traced at full resolution.
        quads.append((quad([(-1.5, 1.2, 1), (1.5, 1.2, 1), (1.5, 1.28, 1), (-1.5, 1.28, 1)], (0, 0, 1)), 0))
        quads.append((quad([(1.2, -1.5, 1), (1.28, -1.5, 1), (1.28, 0.9, 1), (1.2, 0.9, 1)], (0, 0, 1)), 0))
    scene = quad_scene(quads, [Material("grey")], [], (0, -1, 1), (0, 0, 0))
    c2w = np.linalg.inv(cam.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)))
    scene.camera = Camera(c2w, type="ORTHO", ortho_scale=3.8)
    return scene


def _upsample(engine, scene, scale, field):
    """Render the G-buffer, fill the low-resolution texture with field(position (..., 3)) → (..., 4) at the pixels
    the trace would gather at, upsample. Returns (positions (H, W, 4), result (H, W, 4), marked), GL row order."""
    engine.render(scene, RenderSettings("none", W, H))
    pipe = engine.pipeline

    def run(ctx):
        gbuffer = pipe.cache.entries["gbuffer"].value
        pos = np.frombuffer(gbuffer.textures["position"].read(), np.float32).reshape(H, W, 4)
        lw, lh = -(-W // scale), -(-H // scale)
        qx = np.minimum(np.arange(lw) * scale + scale // 2, W - 1)
        qy = np.minimum(np.arange(lh) * scale + scale // 2, H - 1)
        low = field(pos[np.ix_(qy, qx)][..., :3].astype(np.float64)).astype(np.float32)
        tex = ctx.texture((lw, lh), 4, np.ascontiguousarray(low).tobytes(), dtype="f4")
        try:
            out, marked = vct_upsample.joint_bilateral(ctx, pipe.programs, gbuffer, tex, scale, SIGMA)
            data = np.frombuffer(out.read(), np.float32).reshape(H, W, 4).copy()
            out.release()
        finally:
            tex.release()
        return pos, data, marked
    return engine.worker.call(run)


def _affine(p):
    x, y = p[..., 0], p[..., 1]
    return np.stack([1 + 0.3 * x, 1 - 0.2 * y, 0.7 + 0.1 * x + 0.15 * y, 0.9 + 0 * x], axis=-1)


@pytest.mark.parametrize("scale", [2, 4])
def test_constant_and_affine_fields_come_back_exactly(engine, scale):
    scene = _top_view(with_plate=False)
    pos, out, marked = _upsample(engine, scene, scale, lambda p: np.broadcast_to([0.25, 0.5, 1.0, 0.8],
                                                                                  p.shape[:-1] + (4,)))
    hit = pos[..., 3] > 0.5
    assert hit.all() and marked == 0
    # Weights are normalised, so a constant is reproduced to float32 rounding (1e-6 relative).
    np.testing.assert_allclose(out[hit], np.broadcast_to([0.25, 0.5, 1.0, 0.8], out[hit].shape), rtol=1e-6)
    pos, out, marked = _upsample(engine, scene, scale, _affine)
    # Interior pixels (between sample rows/columns; at the borders the clamped lookups extend the last sample, so the
    # field is held constant there instead): bilinear weights of an affine field are exact; float32 rounding of
    # positions (~1e-7 m) and weights: 1e-5.
    lo, hi_x, hi_y = scale // 2, (-(-W // scale) - 1) * scale + scale // 2, (-(-H // scale) - 1) * scale + scale // 2
    inner = np.zeros_like(hit)
    inner[lo:hi_y + 1, lo:hi_x + 1] = True
    exact = _affine(pos[..., :3].astype(np.float64))
    err = np.abs(out - exact)[inner].max()
    print(f"scale {scale}: affine field, max error over {inner.sum()} interior pixels {err:.2e}")
    assert err < 1e-5


@pytest.mark.parametrize("scale", [2, 4])
def test_no_light_crosses_a_depth_discontinuity(engine, scale):
    scene = _top_view(with_plate=True)
    plate_value, floor_value = np.array([1.0, 2.0, 3.0, 1.0]), np.array([0.1, 0.2, 0.3, 0.5])

    def by_surface(p):
        return np.where((p[..., 2] > 0.5)[..., None], plate_value, floor_value)
    pos, out, marked = _upsample(engine, scene, scale, by_surface)
    on_plate = pos[..., 2] > 0.5
    own = np.where(on_plate[..., None], plate_value, floor_value)
    fixup = out[..., 3] == -1.0
    assert marked == int(fixup.sum())
    # Surfaces 1 m apart with σ = 6 cm: the other surface's weight is e^(−256) = 0 in float32, so every pixel not
    # marked holds exactly its own surface's value (float32 rounding of the weighted mean: 1e-6).
    err = np.abs(out - own)[~fixup].max()
    edge = np.zeros_like(on_plate)
    edge[:, 1:] |= on_plate[:, 1:] != on_plate[:, :-1]
    edge[1:, :] |= on_plate[1:, :] != on_plate[:-1, :]
    print(f"scale {scale}: {marked} pixels marked for a full-resolution trace ({edge.sum()} pixels border the "
          f"plate), max error elsewhere {err:.2e}")
    assert err < 1e-6
    # Marked pixels are only those next to the plate's outline (within one sample spacing of it).
    near = edge.copy()
    for _ in range(scale):
        near[1:] |= near[:-1]
        near[:-1] |= near[1:]
        near[:, 1:] |= near[:, :-1]
        near[:, :-1] |= near[:, 1:]
    assert not (fixup & ~near).any()
    assert marked < 0.5 * on_plate.sum()
    if scale == 4:
        assert marked > 0  # the strips (measured count printed above)


def test_pipeline_reduced_resolution_stays_close_to_full(engine):
    scene = _sunlit_room()
    results = {}
    for scale in (1, 2, 4):
        r = engine.render(scene, RenderSettings("vct", W, H, vct=VctSettings(resolution=32, indirect_scale=scale)))
        results[scale] = r
        assert (scale == 1) == ("fixup_pixels" not in r.info)
    hit = results[1].passes["Depth"][..., 0] < 1e9
    ref = results[1].passes["Diffuse Indirect"][hit]
    for scale in (2, 4):
        di = results[scale].passes["Diffuse Indirect"][hit]
        rel = float(np.abs(di - ref).sum() / np.abs(ref).sum())
        ao = float(np.abs(results[scale].passes["AO"][hit] - results[1].passes["AO"][hit]).mean())
        print(f"scale {scale}: Diffuse Indirect rel-L1 vs scale 1 {rel:.4f}, AO mean abs diff {ao:.4f}, "
              f"fix-up pixels {results[scale].info['fixup_pixels']}")
        # The gathers vary over a voxel (6 cm here) while samples are 2–4 pixels (≈ 5–10 cm) apart: measured
        # rel-L1 printed above; bounds 5% (s = 2) and 10% (s = 4).
        assert rel < (0.05 if scale == 2 else 0.10)
        assert np.isfinite(di).all() and di.min() >= 0.0
        assert results[scale].passes["AO"][hit].min() >= 0.0  # every marked pixel (AO = −1) was traced again
