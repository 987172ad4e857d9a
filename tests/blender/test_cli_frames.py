# SPDX-License-Identifier: GPL-3.0-or-later
"""`bounce-gi render --frames A-B` (addon/cli/frames.py) on the animated example, as users run it: bad ranges and
output patterns are one error line and write nothing; a range reuses the passes an unchanged input allows, and a
reused pass gives what a fresh render gives. The command-line helpers and fixtures are test_cli.py's."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from test_cli import ROOT, assert_bad_input, describe, env, run, snapshot  # noqa: F401  (env: a fixture)


@pytest.fixture(scope="module")
def animated(tmp_path_factory, env):  # noqa: F811
    """cornell_animated.blend (examples/scenes/animated.py): light moves at frame 2, camera at 3, box+colour at 4."""
    path = tmp_path_factory.mktemp("animated") / "cornell_animated.blend"
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import bpy; from examples import scenes; "
            "scenes.save('cornell_animated', sys.argv[2])")
    proc = subprocess.run([sys.executable, "-c", code, ROOT, str(path)], capture_output=True, text=True,
                          timeout=180, cwd=ROOT, env=env)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return path


# id -> (argument builder (animated .blend, tmp dir) -> args, fragments of the error line)
ERROR_CASES = {
    "frames_not_a_range": (lambda b, t: ["render", b, "--frames", "1-x", "--out",
                                         t / "f_####.exr"], ["--frames 1-x", "expected A-B"]),
    "frames_reversed": (lambda b, t: ["render", b, "--frames", "3-1", "--out",
                                      t / "f_####.exr"], ["comes before"]),
    "frames_without_hashes": (lambda b, t: ["render", b, "--frames", "1-3", "--out",
                                            t / "o.exr"], ["3 frames need ####"]),
    "frames_wrong_suffix": (lambda b, t: ["render", b, "--frames", "1-2", "--out",
                                          t / "f_##.png"], [".exr"]),
    "frames_out_dir_missing": (lambda b, t: ["render", b, "--frames", "1-2", "--out",
                                             t / "nowhere" / "f_##.exr"], ["does not exist"]),
}


@pytest.mark.parametrize("case", sorted(ERROR_CASES))
def test_bad_frames_input(env, animated, tmp_path, case):  # noqa: F811
    build_args, fragments = ERROR_CASES[case]
    before = snapshot(animated.parent, tmp_path)
    proc = run(env, *build_args(animated, tmp_path), "--json", cwd=tmp_path)
    assert_bad_input(proc, *fragments)
    assert snapshot(animated.parent, tmp_path) == before, "an error must write nothing"


def test_render_frames_reuses_unchanged_passes(env, animated, tmp_path):  # noqa: F811
    # cornell_animated changes one kind of input a frame (examples/scenes/animated.py): the light at frame 2, the
    # camera at frame 3, an object and a material at frame 4. One engine renders them all, so its pass cache must
    # reuse exactly what each change leaves alone, and a reused pass must give what a fresh render gives.
    from bounce_gi.gpu_kernels.output.exr import read_passes

    lpv = ["--method", "lpv", "--lpv", "resolution=16", "--res", 32, 24]
    proc = run(env, "render", animated, "--frames", "1-4", *lpv, "--out",
               tmp_path / "frame_####.exr", "--json")
    assert proc.returncode == 0, describe(proc)
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    frames = report["frames"]
    print({f["frame"]: (round(f["seconds"], 3), f["skipped"]) for f in frames}, report["seconds"])
    assert [f["frame"] for f in frames] == [1, 2, 3, 4]
    assert sorted(os.listdir(tmp_path)) == [f"frame_000{i}.exr" for i in (1, 2, 3, 4)]
    reused = [set(f["skipped"]) for f in frames]
    assert reused[0] == set()                                            # a fresh engine: everything runs
    assert {"geometry", "textures", "gbuffer"} <= reused[1] and "shadow_maps" not in reused[1]   # light moved
    assert {"geometry", "textures", "shadow_maps"} <= reused[2] and "gbuffer" not in reused[2]   # camera moved
    assert not {"geometry", "textures", "gbuffer", "shadow_maps"} & reused[3]                    # object, material
    assert all(f["seconds"] > 0 and f["render_seconds"] >= 0 for f in frames)
    assert report["seconds"]["total"] == pytest.approx(sum(f["seconds"] for f in frames))
    progress = [line for line in proc.stderr.splitlines() if "] " in line and " frame " in line]
    assert len(progress) == 4 and "4/4 frame 4" in progress[-1] and "reused geometry" in progress[1], proc.stderr

    direct = [read_passes(str(tmp_path / f"frame_000{i}.exr"))["Diffuse Direct"] for i in (1, 2, 3, 4)]
    for a, b in zip(direct, direct[1:]):
        assert not np.array_equal(a, b), "consecutive frames rendered the same image"
    # Frame 3 alone, in a fresh process: bit for bit what frame 3 gave after reusing frame 2's light transport
    # (same inputs, same deterministic shaders on the same driver; the voxel sums are fixed-point atomics).
    alone = run(env, "render", animated, "--frames", "3", *lpv, "--out",
                tmp_path / "alone.exr")
    assert alone.returncode == 0, describe(alone)
    assert "wrote 1 frame to" in alone.stdout
    fresh, reused_3 = read_passes(str(tmp_path / "alone.exr")), read_passes(str(tmp_path / "frame_0003.exr"))
    for name in ("Combined", "Diffuse Direct", "Diffuse Indirect"):
        assert np.array_equal(fresh[name], reused_3[name]), name
