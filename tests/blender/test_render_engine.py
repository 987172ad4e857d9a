# SPDX-License-Identifier: GPL-3.0-or-later
"""The BOUNCE_GI render engine as users get it: the built zip installed into bpy under a temporary
BLENDER_USER_RESOURCES and enabled, then F12 (`bpy.ops.render.render(write_still=True)`, what
`blender -b FILE -E BOUNCE_GI -f N` runs), an animation (`-a`), disable/enable cycles and error reports.

Each case runs in its own subprocess (BLENDER_USER_RESOURCES must be set before bpy is imported, and
register/unregister side effects must not leak) and prints what it sees. Scenes are tiny (64x48 at most)
and use method NONE or LPV: the point is the plumbing, not accuracy.
"""
import glob
import os
import subprocess
import sys
import textwrap

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXT_MODULE = "bl_ext.user_default.bounce_gi"

# Prepended to every case: build an example scene (factory settings first, so before the extension is enabled)
# and save it, install and enable the zip, open the .blend again as `blender -b FILE` would, and helpers.
PRELUDE = """
import importlib, os, sys, threading
import bpy
import numpy as np
from examples import scenes

zip_path, mod, tmp = sys.argv[1], sys.argv[2], sys.argv[3]
BLEND = os.path.join(tmp, "scene.blend")
scenes.save(os.environ.get("CASE_SCENE", "cornell"), BLEND)   # the example scene a case renders
print("install", bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                          enable_on_install=True))
assert mod in bpy.context.preferences.addons, "extension not enabled"
assert sys.modules[mod].__file__.startswith(os.environ["BLENDER_USER_RESOURCES"]), sys.modules[mod].__file__


def ext(name):
    # A module of the installed extension: ext("gpu_kernels.output.exr").
    return importlib.import_module(mod + "." + name)


def open_blend(engine="BOUNCE_GI", method="NONE", size=(64, 48), percentage=100):
    bpy.ops.wm.open_mainfile(filepath=BLEND)
    scene = bpy.context.scene
    scene.render.engine = engine                      # blender -E BOUNCE_GI
    scene.bounce_gi.method = method
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = *size, percentage
    im = r.image_settings
    if hasattr(im, "media_type"):                     # Blender 5: the media type comes first
        im.media_type = "MULTI_LAYER_IMAGE"
    im.file_format, im.color_depth = "OPEN_EXR_MULTILAYER", "32"
    return scene


def gpu_threads():
    return [t for t in threading.enumerate() if t.name == "bounce-gi-gpu"]


def engines():
    # Registered ones only: an unregistered class stays among the subclasses while Python holds it.
    return [getattr(c, "bl_idname", c.__name__) for c in bpy.types.RenderEngine.__subclasses__() if c.is_registered]
"""


@pytest.fixture(scope="module")
def linux_zip(tmp_path_factory):
    """The Linux zip built by tools/package.py into a temporary folder (dist/ is left alone)."""
    out = tmp_path_factory.mktemp("dist")
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "package.py"), "--output-dir", str(out)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (path,) = glob.glob(os.path.join(out, "*linux_x64.zip"))
    return path


def run_case(linux_zip, tmp_path, body: str, env: dict | None = None, timeout: float = 240):
    """Run PRELUDE + body in a fresh interpreter; fail with its output unless it ends with CASE OK.
    Returns (stdout, stderr)."""
    code = PRELUDE + textwrap.dedent(body) + "\nprint('CASE OK')\n"
    env = {**os.environ, "BLENDER_USER_RESOURCES": str(tmp_path / "user"), **(env or {})}
    env.pop("PYTHONPATH", None)  # the installed copy only, never this checkout under the name bounce_gi
    proc = subprocess.run([sys.executable, "-c", code, linux_zip, EXT_MODULE, str(tmp_path)],
                          capture_output=True, text=True, timeout=timeout, cwd=ROOT, env=env)
    output = f"--- exit status {proc.returncode}\n--- stdout\n{proc.stdout}\n--- stderr\n{proc.stderr}"
    print(output)
    assert proc.returncode == 0 and "CASE OK" in proc.stdout, output
    return proc.stdout, proc.stderr


def test_f12_writes_every_pass_as_a_direct_render_does(linux_zip, tmp_path):
    # Exact equality is the expectation: the EXR holds the float32 passes the same code computed (same extraction,
    # settings and shaders on the same driver), written losslessly (32-bit float, zip); Blender only flips the rows
    # back. The direct render runs on a second, fresh Engine, so nothing comes from the first one's cache.
    run_case(linux_zip, tmp_path, """
        import time
        print("render engines", engines())
        assert "BOUNCE_GI" in engines()
        scene = open_blend(method="LPV", size=(128, 96), percentage=50)    # 64 x 48 after the percentage
        scene.render.filepath = os.path.join(tmp, "f12")
        start = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        print(f"F12 64x48 LPV: {time.perf_counter() - start:.2f} s")
        path = os.path.join(tmp, "f12.exr")
        got = ext("gpu_kernels.output.exr").read_passes(path)
        print({k: v.shape for k, v in got.items()})

        names = ext("gpu_kernels.compose").PASS_NAMES
        assert [p[0] for p in ext("ui.render_engine").PASSES] == list(names)
        assert set(names) <= set(got), sorted(set(names) - set(got))
        scene_data = ext("addon.extract").extract_scene(bpy.context.evaluated_depsgraph_get(), resolution=(64, 48))
        direct = ext("gpu_kernels.engine").Engine()
        want = direct.render(scene_data, ext("gpu_kernels.settings").RenderSettings(method="lpv", width=64, height=48))
        direct.shutdown()
        for name in names:
            a, b = got[name], want.passes[name].reshape(48, 64, -1)
            diff = float(np.abs(a - b).max()) if a.shape == b.shape else None
            print(f"{name:18s} shape {a.shape} max |F12 - direct| {diff} mean {float(b.mean()):.4g}")
            assert a.shape == b.shape, (name, a.shape, b.shape)
            assert np.array_equal(a, b), (name, diff)
        assert got["Combined"][..., :3].max() > 0 and got["Diffuse Indirect"].max() > 0  # lit, with GI
        assert np.abs(got["Combined"][:8] - got["Combined"][-8:]).max() > 0   # not flipped into symmetry by luck

        # Render Region: the full frame is rendered and the region copied out. Blender places it in the frame
        # (alpha 0 around it) or, with Crop, writes the region alone. x 16..48, y 4..24 from the bottom (Blender
        # truncates 0.1 * 48 = 4.8 to 4), so rows 24..44 from the top.
        r = scene.render
        r.use_border, r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = True, 0.25, 0.75, 0.1, 0.5
        for crop in (False, True):
            r.use_crop_to_border = crop
            r.filepath = os.path.join(tmp, f"region_crop{int(crop)}")
            bpy.ops.render.render(write_still=True)
            region = ext("gpu_kernels.output.exr").read_passes(r.filepath + ".exr")["Combined"]
            print("region, crop", crop, region.shape)
            if crop:
                assert np.array_equal(region, got["Combined"][24:44, 16:48])
            else:
                inside = np.zeros((48, 64), bool)
                inside[24:44, 16:48] = True
                assert np.array_equal(region[inside], got["Combined"][inside]) and not region[~inside].any()
    """)


def test_animation_writes_one_file_per_frame(linux_zip, tmp_path):
    run_case(linux_zip, tmp_path, """
        scene = open_blend(size=(32, 24))
        light = next(o for o in scene.objects if o.type == "LIGHT")
        for frame, energy in ((1, 20.0), (3, 60.0)):              # keyed: frame 2 is interpolated
            light.data.energy = energy
            light.data.keyframe_insert("energy", frame=frame)
        scene.frame_start, scene.frame_end = 1, 3
        scene.render.filepath = os.path.join(tmp, "anim_")
        bpy.ops.render.render(animation=True)
        files = sorted(f for f in os.listdir(tmp) if f.startswith("anim_"))
        print("files", files)
        assert files == ["anim_0001.exr", "anim_0002.exr", "anim_0003.exr"], files
        means = [float(ext("gpu_kernels.output.exr").read_passes(os.path.join(tmp, f))["Diffuse Direct"].mean())
                 for f in files]
        print("mean Diffuse Direct per frame", means)
        assert means[0] > 0 and means[0] < means[1] < means[2], means   # each frame's own light energy
    """)


def test_animation_reuses_the_engine_between_frames(linux_zip, tmp_path):
    # `-a` on cornell_animated (examples/scenes/animated.py): the light moves at frame 2, the camera at frame 3.
    # Blender calls render() once a frame; the one process-wide engine keeps its pass cache, and each frame's log
    # line says what it reused.
    out, _ = run_case(linux_zip, tmp_path, """
        scene = open_blend(method="LPV", size=(32, 24))
        scene.bounce_gi.quality = "DRAFT"
        scene.frame_start, scene.frame_end = 1, 3
        scene.render.filepath = os.path.join(tmp, "anim_")
        engine = ext("gpu_kernels.engine").get_engine()
        bpy.ops.render.render(animation=True)
        assert ext("gpu_kernels.engine").get_engine() is engine, "a new engine: nothing could be reused"
        files = sorted(f for f in os.listdir(tmp) if f.startswith("anim_"))
        print("files", files)
        assert files == ["anim_0001.exr", "anim_0002.exr", "anim_0003.exr"], files
    """, env={"CASE_SCENE": "cornell_animated"})
    lines = [line for line in out.splitlines() if line.startswith("Bounce GI: frame ")]
    assert len(lines) == 3, out
    reused = [set(line.partition("; reused ")[2].split(", ")) for line in lines]
    assert reused[0] == {"nothing"}, lines
    assert {"geometry", "textures", "gbuffer"} <= reused[1] and "shadow_maps" not in reused[1], lines
    assert {"geometry", "textures", "shadow_maps"} <= reused[2] and "gbuffer" not in reused[2], lines


def test_disable_enable_stops_the_worker_and_renders_again(linux_zip, tmp_path):
    run_case(linux_zip, tmp_path, """
        scene = open_blend(size=(32, 24))
        previous = None
        for round_ in range(3):
            scene.render.filepath = os.path.join(tmp, f"round{round_}")
            bpy.ops.render.render(write_still=True)
            engine = ext("gpu_kernels.engine").get_engine()
            print("round", round_, "threads after render", gpu_threads(), "engine", id(engine))
            assert len(gpu_threads()) == 1 and engine is not previous
            assert os.path.exists(os.path.join(tmp, f"round{round_}.exr"))
            previous = engine

            bpy.ops.preferences.addon_disable(module=mod)
            print("  disabled: threads", gpu_threads(), "engines", engines())
            assert gpu_threads() == [] and "BOUNCE_GI" not in engines()
            assert "BOUNCE_GI" not in bpy.types.DATA_PT_light.COMPAT_ENGINES
            assert not engine.worker.thread.is_alive() and engine.pipeline is None
            bpy.ops.preferences.addon_enable(module=mod)
            assert "BOUNCE_GI" in engines() and hasattr(bpy.types.Scene, "bounce_gi")
            # Blender's own panels (light, camera, output ...) list the engine again; ours is registered.
            assert "BOUNCE_GI" in bpy.types.DATA_PT_light.COMPAT_ENGINES and hasattr(bpy.types, "RENDER_PT_bounce_gi")
            scene = bpy.context.scene
            assert scene.render.engine == "BOUNCE_GI", scene.render.engine
        scene.render.filepath = os.path.join(tmp, "after")
        bpy.ops.render.render(write_still=True)
        got = ext("gpu_kernels.output.exr").read_passes(os.path.join(tmp, "after.exr"))
        first = ext("gpu_kernels.output.exr").read_passes(os.path.join(tmp, "round0.exr"))
        assert np.array_equal(got["Combined"], first["Combined"]) and got["Combined"].max() > 0
        assert len(gpu_threads()) == 1
    """)


def test_errors_are_one_line_reports(linux_zip, tmp_path):
    out, err = run_case(linux_zip, tmp_path, """
        def render_error(scene, name):
            scene.render.filepath = os.path.join(tmp, name)
            try:
                bpy.ops.render.render(write_still=True)
            except RuntimeError as ex:   # how bpy.ops surfaces an ERROR report
                msg = str(ex).strip()
                print(name, "->", repr(msg))
                assert msg.count("\\n") == 0 and "Traceback" not in msg, msg
                return msg
            raise AssertionError(name + ": the render reported no error")

        scene = open_blend(size=(32, 24))
        scene.camera.data.type = "PANO"            # extraction refuses it: our own one-line report
        assert "PANO" in render_error(scene, "pano")
        scene.camera.data.type = "PERSP"
        scene.camera = None                        # Blender refuses before calling the engine
        assert "camera" in render_error(scene, "nocam").lower()
        print("files", sorted(os.listdir(tmp)))
        assert not [f for f in os.listdir(tmp) if f.endswith(".exr")], "an error still wrote a file"
    """)
    assert "Traceback" not in err, err


def test_no_opengl_43_is_a_one_line_report(linux_zip, tmp_path):
    # Mesa's llvmpipe offering only OpenGL 4.1 (as macOS does): the engine cannot make its context.
    out, err = run_case(linux_zip, tmp_path, """
        scene = open_blend(size=(32, 24))
        scene.render.filepath = os.path.join(tmp, "nogl")
        try:
            bpy.ops.render.render(write_still=True)
        except RuntimeError as ex:
            msg = str(ex).strip()
            print("no GL 4.3 ->", repr(msg))
            assert "OpenGL 4.3" in msg and msg.count("\\n") == 0, msg
        else:
            raise AssertionError("rendered without OpenGL 4.3")
        assert not os.path.exists(os.path.join(tmp, "nogl.exr"))
    """, env={"MESA_GL_VERSION_OVERRIDE": "4.1"})
    assert "Traceback" not in err, err
