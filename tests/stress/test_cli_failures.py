# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi render` (background Blender, a real subprocess) when the input or the GPU is bad: a NaN vertex costs
only its object (exit 0, a warning naming it); no OpenGL 4.3, a shader the driver rejects, the GPU out of memory
mid-render and a grid too large for the memory each give exit 2, one stderr line, no traceback and no file; and the
next run works once the cause is gone. Faults the driver cannot be asked for are injected by a small driver script
(FAULTS) that patches moderngl and then runs the CLI's own main()."""
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CLI = [sys.executable, "-m", "bounce_gi.addon.cli"]
RES = ("--res", "32", "24")
SMALL = {"lpv": ("--lpv", "resolution=8", "rsm_resolution=32"), "vct": ("--vct", "resolution=16", "diffuse_cones=5")}

MAKE_BLENDS = r"""
import os, sys
import bpy
sys.path.insert(0, sys.argv[1])
from examples import scenes
out = sys.argv[2]
scenes.save("cornell", os.path.join(out, "cornell.blend"))
scenes.build("cornell")
bpy.data.objects["TallBox"].data.vertices[0].co = (float("nan"), 0.0, 0.0)
bpy.context.preferences.filepaths.save_version = 0
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "nan_vertex.blend"))
"""

FAULTS = {
    "shader": "moderngl.Context.compute_shader = lambda self, *a, **k: (_ for _ in ()).throw("
              "moderngl.Error('0:7(1): error: syntax error, unexpected NEW_IDENTIFIER'))",
    "out of memory": "import itertools; _n = itertools.count(); _t = moderngl.Context.texture3d\n"
                     "moderngl.Context.texture3d = lambda self, *a, **k: _t(self, *a, **k) if next(_n) < 2 else "
                     "(_ for _ in ()).throw(moderngl.Error('GL_OUT_OF_MEMORY'))",
    "little memory": "import bounce_gi.gpu_kernels.settings as s; s.available_memory = lambda: 2 ** 30",
}
DRIVER = "import sys, moderngl\n{fault}\nfrom bounce_gi.addon.cli import main\nsys.exit(main(sys.argv[1:]))\n"


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    base = tmp_path_factory.mktemp("stress_cli")
    e = {k: v for k, v in os.environ.items() if k not in ("BOUNCE_GI_DEBUG", "MESA_GL_VERSION_OVERRIDE")}
    e.update(BLENDER_USER_RESOURCES=str(base / "blender_user"), BOUNCE_GI_CACHE=str(base / "cache"))
    return e


@pytest.fixture(scope="module")
def blends(tmp_path_factory, env):
    d = tmp_path_factory.mktemp("stress_blends")
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(MAKE_BLENDS), ROOT, str(d)], capture_output=True,
                          text=True, timeout=300, cwd=ROOT, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return d


def run(env, args, fault=None, extra_env=None):
    cmd = [sys.executable, "-c", DRIVER.format(fault=FAULTS[fault])] if fault else CLI
    return subprocess.run([*cmd, *map(str, args)], capture_output=True, text=True, timeout=300, cwd=ROOT,
                          env={**env, **(extra_env or {})})


def assert_one_line_error(proc, out, *fragments):
    detail = f"exit {proc.returncode}\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}"
    assert proc.returncode == 2, detail
    lines = [l for l in proc.stderr.splitlines() if l.strip()]
    assert len(lines) == 1 and lines[0].startswith("bounce-gi: error: "), detail
    assert "Traceback" not in proc.stderr + proc.stdout, detail
    assert all(f in lines[0] for f in fragments), detail
    assert not out.exists() and not [p for p in out.parent.iterdir() if p.name.startswith(".bounce-gi-")]


def assert_renders(env, blends, out, method="lpv"):
    proc = run(env, ["render", blends / "cornell.blend", "--method", method, *SMALL[method], *RES, "--out", out,
                     "--json"])
    assert proc.returncode == 0 and out.exists(), proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("method", ("lpv", "vct"))
def test_a_nan_vertex_costs_only_its_object(env, blends, tmp_path, method):
    out = tmp_path / "nan.exr"
    proc = run(env, ["render", blends / "nan_vertex.blend", "--method", method, *SMALL[method], *RES, "--out", out,
                     "--json"])
    assert proc.returncode == 0, proc.stderr[-2000:]
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert any("'TallBox'" in w and "NaN" in w for w in report["warnings"]), report["warnings"]
    from bounce_gi.gpu_kernels.output.exr import read_passes

    passes = read_passes(str(out))
    assert all(np.isfinite(p).all() for p in passes.values()) and passes["Combined"][..., :3].max() > 0


def test_no_opengl_43_then_the_driver_is_back(env, blends, tmp_path):
    """Mesa told to offer OpenGL 4.1 only (what macOS and old drivers give): one line; then a normal run works."""
    out = tmp_path / "a.exr"
    proc = run(env, ["render", blends / "cornell.blend", "--method", "lpv", *SMALL["lpv"], *RES, "--out", out],
               extra_env={"MESA_GL_VERSION_OVERRIDE": "4.1"})
    assert_one_line_error(proc, out, "OpenGL 4.3")
    assert_renders(env, blends, out)


@pytest.mark.parametrize("fault, method, fragment", [("shader", "vct", "could not compile a shader"),
                                                     ("out of memory", "vct", "GL_OUT_OF_MEMORY"),
                                                     ("little memory", "vct", "GiB of memory")])
def test_gpu_failures_are_one_line_and_write_nothing(env, blends, tmp_path, fault, method, fragment):
    out = tmp_path / "b.exr"
    args = ["render", blends / "cornell.blend", "--method", method, *RES, "--out", out]
    args += ["--vct", "resolution=256"] if fault == "little memory" else SMALL[method]
    assert_one_line_error(run(env, args, fault=fault), out, fragment)


def test_snapshot_out_of_memory_is_one_line(env, blends, tmp_path):
    """`bounce-gi snapshot` (the viewport's path, Engine.submit_surface) reports the same failure the same way."""
    out = tmp_path / "c.png"
    args = ["snapshot", blends / "cornell.blend", "--method", "vct", *SMALL["vct"], *RES, "--texels", "4096",
            "--out", out]
    assert_one_line_error(run(env, args, fault="out of memory"), out, "GL_OUT_OF_MEMORY")
