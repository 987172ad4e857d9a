# SPDX-License-Identifier: GPL-3.0-or-later
"""gpu_kernels.output.exr: multi-part EXR in Blender 5's layout (docs/conventions.md, Passes), atomic writes, reading real Blender
output, and the sRGB preview tone map."""
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from bounce_gi.gpu_kernels.output import exr as exr_io

oiio = pytest.importorskip("OpenImageIO")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _passes(h=5, w=7, seed=0):
    rng = np.random.default_rng(seed)
    return {
        "Combined": rng.normal(size=(h, w, 4)).astype(np.float32) * 100,
        "Diffuse Direct": rng.uniform(0, 3, (h, w, 3)).astype(np.float32),
        "Diffuse Color": rng.uniform(0, 1, (h, w, 3)).astype(np.float32),
        "Depth": rng.uniform(0.1, 1e10, (h, w)).astype(np.float32),  # 2D in, (h, w, 1) out
        "Normal": rng.normal(size=(h, w, 3)).astype(np.float32),
    }


def test_round_trip_is_exact(tmp_path):
    passes = _passes()
    # Values float32 represents but a lossy or half-float path would not: tiny, huge, negative, subnormal.
    passes["Diffuse Direct"][0, 0] = (1e-30, 3.4e38, -1.5e-42)
    path = tmp_path / "out.exr"
    exr_io.write_passes(str(path), passes)
    back = exr_io.read_passes(str(path))
    assert set(back) == set(passes)
    for name, image in passes.items():
        expected = image if image.ndim == 3 else image[..., None]
        assert back[name].dtype == np.float32
        assert back[name].shape == expected.shape, name
        np.testing.assert_array_equal(back[name], expected, err_msg=name)


def test_layout_matches_blender_multipart(tmp_path):
    path = tmp_path / "layout.exr"
    passes = _passes(h=3, w=4)
    exr_io.write_passes(str(path), passes)
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    parts = []
    sub = 0
    while inp.seek_subimage(sub, 0):
        spec = inp.spec()
        parts.append((spec.getattribute("name"), tuple(spec.channelnames), spec.width, spec.height, str(spec.format)))
        # Each part's pixels are that pass's (read with the 5-argument form, docs/conventions.md).
        data = np.asarray(inp.read_image(sub, 0, 0, spec.nchannels, oiio.FLOAT)).reshape(3, 4, -1)
        name = spec.getattribute("name").split(".", 1)[1]
        image = passes[name] if passes[name].ndim == 3 else passes[name][..., None]
        np.testing.assert_array_equal(data, image)
        sub += 1
    inp.close()
    assert parts == [
        ("ViewLayer.Combined", ("ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                                "ViewLayer.Combined.A"), 4, 3, "float"),
        ("ViewLayer.Diffuse Direct", ("ViewLayer.Diffuse Direct.R", "ViewLayer.Diffuse Direct.G",
                                      "ViewLayer.Diffuse Direct.B"), 4, 3, "float"),
        ("ViewLayer.Diffuse Color", ("ViewLayer.Diffuse Color.R", "ViewLayer.Diffuse Color.G",
                                     "ViewLayer.Diffuse Color.B"), 4, 3, "float"),
        ("ViewLayer.Depth", ("ViewLayer.Depth.Z",), 4, 3, "float"),
        ("ViewLayer.Normal", ("ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z"), 4, 3, "float"),
    ]


def test_write_into_missing_directory_raises_and_leaves_nothing(tmp_path):
    target = tmp_path / "missing" / "out.exr"
    with pytest.raises(OSError):
        exr_io.write_passes(str(target), _passes())
    assert not target.exists() and not target.parent.exists()
    # A "directory" that is a file.
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OSError):
        exr_io.write_passes(str(blocker / "out.exr"), _passes())
    assert sorted(os.listdir(tmp_path)) == ["file"]


def test_failed_write_keeps_old_file_and_no_temporary(tmp_path):
    """OpenEXR refuses a 0-channel part after the temporary file exists: the error must be an OSError, the temporary
    must be gone and an existing file at the target must be untouched (write to temp + rename)."""
    target = tmp_path / "out.exr"
    exr_io.write_passes(str(target), {"Diffuse Color": np.full((2, 2, 3), 0.25, np.float32)})
    before = target.read_bytes()
    with pytest.raises(OSError):
        exr_io.write_passes(str(target), {"Combined": np.ones((2, 2, 4), np.float32),
                                          "Broken": np.zeros((2, 2, 0), np.float32)})
    assert os.listdir(tmp_path) == ["out.exr"]
    assert target.read_bytes() == before
    np.testing.assert_array_equal(exr_io.read_passes(str(target))["Diffuse Color"], 0.25)


def test_read_missing_file_raises_oserror(tmp_path):
    with pytest.raises(OSError):
        exr_io.read_passes(str(tmp_path / "nope.exr"))


BLENDER_RENDER = textwrap.dedent("""
    import sys
    import bpy
    import bmesh

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 16, 12, 100
    layer = scene.view_layers[0]
    layer.use_pass_diffuse_direct = True
    layer.use_pass_diffuse_color = True
    layer.use_pass_z = True

    mat = bpy.data.materials.new("grey")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mesh = bpy.data.meshes.new("floor")
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=20)
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(mat)
    floor = bpy.data.objects.new("floor", mesh)
    scene.collection.objects.link(floor)
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    cam.location = (0, 0, 5)  # looking straight down (-Z) at the floor
    scene.camera = cam
    sun = bpy.data.lights.new("sun", "SUN")
    sun.energy = 2.0  # irradiance 2 W/m² at normal incidence; the sun points down
    sun.angle = 0.0
    scene.collection.objects.link(bpy.data.objects.new("sun", sun))

    settings = scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    scene.render.filepath = sys.argv[1]
    bpy.ops.render.render(write_still=True)
""")


@pytest.fixture(scope="module")
def blender_exr(tmp_path_factory):
    path = tmp_path_factory.mktemp("blender") / "render.exr"
    proc = subprocess.run([sys.executable, "-c", BLENDER_RENDER, str(path)], capture_output=True, text=True,
                          timeout=180, cwd=ROOT)
    assert proc.returncode == 0 and path.exists(), proc.stdout[-3000:] + proc.stderr[-3000:]
    return path


def test_reads_blender_multilayer_exr(blender_exr):
    passes = exr_io.read_passes(str(blender_exr))
    assert {"Combined", "Diffuse Direct", "Diffuse Color", "Depth"} <= set(passes)
    assert passes["Combined"].shape == (12, 16, 4)
    assert passes["Diffuse Direct"].shape == (12, 16, 3)
    assert passes["Diffuse Color"].shape == (12, 16, 3)
    assert passes["Depth"].shape == (12, 16, 1)
    # The values prove each pass came from its own part (the 3-argument read returns the first part for all):
    # Diffuse BSDF albedo 0.5; a 2 W/m² sun overhead on the floor gives Diffuse Direct = E/π; Depth = 5 m;
    # Combined = direct × albedo (nothing else lights or is seen: black world, one plane).
    np.testing.assert_allclose(passes["Diffuse Color"], 0.5, rtol=1e-6)
    np.testing.assert_allclose(passes["Diffuse Direct"], 2 / math.pi, rtol=1e-3)
    np.testing.assert_allclose(passes["Depth"], 5.0, rtol=1e-5)
    np.testing.assert_allclose(passes["Combined"][..., :3], 0.5 * 2 / math.pi, rtol=1e-3)
    np.testing.assert_allclose(passes["Combined"][..., 3], 1.0)


def test_round_trip_of_blender_file_through_our_writer(blender_exr, tmp_path):
    """Blender's file → read → our writer → read gives the same arrays (same layout both ways)."""
    passes = exr_io.read_passes(str(blender_exr))
    exr_io.write_passes(str(tmp_path / "again.exr"), passes)
    again = exr_io.read_passes(str(tmp_path / "again.exr"))
    assert set(again) == set(passes)
    for name in passes:
        np.testing.assert_array_equal(again[name], passes[name], err_msg=name)


def _srgb_reference(v: float) -> int:
    """IEC 61966-2-1 encode, then round to 8 bits."""
    s = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
    return int(math.floor(s * 255 + 0.5))


def test_tonemap_srgb():
    linear = np.array([[[0.0, 1.0, 0.5], [0.002, 0.2, 4.0], [-1.0, 0.0031308, 0.9]]], np.float32)
    out = exr_io.tonemap_srgb(linear)
    assert out.dtype == np.uint8 and out.shape == (1, 3, 3)
    assert out[0, 0].tolist() == [0, 255, 188]  # 0 → 0, 1 → 255, 0.5 → 1.055·0.5^(1/2.4) − 0.055 = 0.7354 → 188
    expected = [_srgb_reference(min(max(float(v), 0.0), 1.0)) for v in linear.ravel()]
    assert out.ravel().tolist() == expected
    # Alpha is dropped, exposure is in stops: 0.25 at +1 stop encodes like 0.5.
    rgba = np.full((1, 1, 4), 0.25, np.float32)
    assert exr_io.tonemap_srgb(rgba, exposure=1.0).tolist() == [[[188, 188, 188]]]
