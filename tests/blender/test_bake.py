# SPDX-License-Identifier: GPL-3.0-or-later
"""Bake GI to Color Attribute (`bounce_gi.bake_color_attribute`, ui/bake.py) in background Blender: per-vertex
error against Cycles' vertex bake on two example scenes, the mesh data left exactly as it was apart from the one
attribute, the options, bad input, and Esc in the modal path writing nothing.

Undo: background Blender runs `ed.undo` / `ed.redo` over steps pushed with `ed.undo_push`, but pushes no step
after an operator by itself (the window manager does that interactively, for operators with the UNDO option, which
the bake has). So the undo test pushes the step the window manager would, and checks that undoing it restores every
mesh exactly and redoing it brings the bake back; the other tests check that the bake changes nothing but the
"BounceGI" attributes, in one operator call, and that a failed or cancelled one changes nothing at all.
"""
import os
import subprocess
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

PRELUDE = """
import os, sys
import bpy
import numpy as np
import bounce_gi
from bounce_gi.ui import bake
from examples import scenes
from bounce_gi.addon.reference.vertex_bake import cycles_vertex_bake, rel_l1
bounce_gi.register()


def mesh_state(objects):
    # Everything of each mesh that a bake must not touch: positions, corners, faces, every attribute but BounceGI.
    out = {}
    for o in objects:
        m = o.data
        co = np.empty(len(m.vertices) * 3, np.float32); m.vertices.foreach_get("co", co)
        lv = np.empty(len(m.loops), np.int64); m.loops.foreach_get("vertex_index", lv)
        out[o.name, "co"], out[o.name, "loops"] = co, lv
        for a in m.attributes:
            size = {"FLOAT": 1, "FLOAT2": 2, "FLOAT_VECTOR": 3, "FLOAT_COLOR": 4}.get(a.data_type)
            if a.name != bake.ATTRIBUTE and size:
                key = {"FLOAT": "value", "FLOAT_COLOR": "color"}.get(a.data_type, "vector")
                v = np.empty(len(a.data) * size, np.float32)
                a.data.foreach_get(key, v)
                out[o.name, a.name] = v
        out[o.name, "names"] = sorted(a.name for a in m.attributes if a.name != bake.ATTRIBUTE)
    return out


def same_state(a, b):
    assert a.keys() == b.keys(), (sorted(set(a) ^ set(b)))
    for k in a:
        assert np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k], k


def baked(objects):
    out = {}
    for o in objects:
        attr = o.data.color_attributes[bake.ATTRIBUTE]
        assert (attr.domain, attr.data_type) == ("POINT", "FLOAT_COLOR"), (attr.domain, attr.data_type)
        v = np.empty(len(attr.data) * 4, np.float32); attr.data.foreach_get("color", v)
        out[o.name] = v.reshape(-1, 4)[:, :3].copy()
    return out
"""


def run_case(tmp_path, body: str, timeout: float = 600) -> str:
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    os.symlink(ROOT, pkg / "bounce_gi")
    code = PRELUDE + textwrap.dedent(body) + "\nprint('CASE OK')\n"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(pkg), ROOT]),
           "BLENDER_USER_RESOURCES": str(tmp_path / "user")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout, cwd=ROOT,
                          env=env)
    output = f"--- exit status {proc.returncode}\n--- stdout\n{proc.stdout[-6000:]}\n--- stderr\n{proc.stderr[-4000:]}"
    print(output)
    assert proc.returncode == 0 and "CASE OK" in proc.stdout, output
    return proc.stdout


def test_bake_against_cycles_vertex_bake_and_mesh_data_untouched(tmp_path):
    # Per-vertex rel-L1 against Cycles' vertex bake, LPV at its Medium settings (32^3, 8 bounces) with the bake's
    # RSM twice as fine as a render's (ui/bake.BAKE_RSM_SCALE), INSET_CELLS["lpv"] = 0.3, measured 2026-12-05: 0.191 on
    # the Cornell box, 0.133 on spot_room (with the render's RSM: 0.232 and 0.134; the Cornell box missed the issue's
    # target of 0.20, its room corners 1.1-1.9x too bright). Bound: the measurement + 2 x the noise floor of this
    # test's 1024-spp two-seed reference (half the seeds' rel-L1, ~0.02: the reference's own error, as
    # tests/accuracy/test_examples_vs_cycles.py argues) + 0.001 for float rounding, or the target where the
    # measurement meets it and the target is lower, so a regression beyond the reference's noise fails and the target,
    # once met, stays met.
    measured = {"cornell": 0.191, "spot_room": 0.133}
    target = 0.20
    run_case(tmp_path, """
        measured, target = """ + repr(measured) + ", " + repr(target) + """
        for name in ("cornell", "spot_room"):
            scenes.build(name)
            scene = bpy.context.scene
            scene.bounce_gi.method, scene.bounce_gi.quality = "LPV", "MEDIUM"
            meshes = [o for o in scene.objects if o.type == "MESH"]
            ref, seeds, cycles_s = cycles_vertex_bake(meshes, samples=1024)
            floor = 0.5 * rel_l1(seeds[0], seeds[1])
            before = mesh_state(meshes)
            assert bpy.ops.bounce_gi.bake_color_attribute() == {"FINISHED"}
            ours = baked(meshes)
            err = rel_l1(ours, ref)
            print(f"{name}: per-vertex rel-L1 {err:.3f} (reference noise {floor:.3f}, Cycles 1024 spp x 2 "
                  f"{cycles_s:.2f} s), vertices {sum(len(v) for v in ours.values())}")
            bound = measured[name] + 2 * floor + 0.001
            assert err <= (min(bound, target) if measured[name] <= target else bound), (name, err, floor)
            after = mesh_state(meshes)
            same_state(before, after)             # nothing but the BounceGI attribute changed ...
            assert all(bake.ATTRIBUTE in o.data.color_attributes for o in meshes)

            # ... and baking again overwrites it in place: one attribute, the same values (same inputs, same job).
            assert bpy.ops.bounce_gi.bake_color_attribute() == {"FINISHED"}
            assert all(len([a for a in o.data.attributes if a.name == bake.ATTRIBUTE]) == 1 for o in meshes)
            again = baked(meshes)
            assert all(np.array_equal(again[k], ours[k]) for k in ours)

            # Options: direct light added, then times the albedo (Diffuse BSDF colours, constant per mesh here).
            assert bpy.ops.bounce_gi.bake_color_attribute(include_direct=True) == {"FINISHED"}
            direct = baked(meshes)
            assert all((direct[k] >= ours[k] - 1e-6).all() for k in ours) and \\
                sum(direct[k].sum() for k in ours) > 1.05 * sum(ours[k].sum() for k in ours)
            assert bpy.ops.bounce_gi.bake_color_attribute(include_albedo=True) == {"FINISHED"}
            albedo = baked(meshes)
            for o in meshes:
                np.testing.assert_allclose(albedo[o.name], ours[o.name] * bake.vertex_albedo(o), rtol=1e-5, atol=1e-7)
    """)


def test_bad_input_and_esc_write_nothing(tmp_path):
    run_case(tmp_path, """
        from types import SimpleNamespace
        from bounce_gi.ui.bake_operator import BOUNCE_GI_OT_bake_color_attribute as Op
        scenes.build("cornell")
        scene = bpy.context.scene
        scene.bounce_gi.method, scene.bounce_gi.quality = "LPV", "DRAFT"
        meshes = [o for o in scene.objects if o.type == "MESH"]
        before = mesh_state(meshes)

        bpy.ops.object.select_all(action="DESELECT")
        try:
            bpy.ops.bounce_gi.bake_color_attribute(selected_only=True)
        except RuntimeError as ex:   # how bpy.ops surfaces an ERROR report
            msg = str(ex).strip()
            print("nothing selected ->", repr(msg))
            assert "no visible mesh" in msg and "selected" in msg and msg.count("\\n") == 0, msg
        else:
            raise AssertionError("baked with nothing selected")
        same_state(before, mesh_state(meshes))

        # The modal path, Esc before the GPU job is done: nothing written.
        log = []
        class WM:
            def event_timer_add(self, step, window=None): log.append("timer+"); return "timer"
            def event_timer_remove(self, timer): log.append("timer-")
            def modal_handler_add(self, op): log.append("handler")
        class Workspace:
            def status_text_set(self, text): log.append(("status", text))
        class FakeOp:
            modal, cancel, _cleanup, _fail, _done = Op.modal, Op.cancel, Op._cleanup, Op._fail, Op._done
            selected_only, include_direct, include_albedo, _timer = False, False, False, "timer"
            def report(self, kind, msg): log.append((sorted(kind)[0], msg))
        ctx = SimpleNamespace(scene=scene, window=None, window_manager=WM(), workspace=Workspace(),
                              view_layer=bpy.context.view_layer, selected_objects=[],
                              evaluated_depsgraph_get=bpy.context.evaluated_depsgraph_get)
        op = FakeOp()
        op._pending = bake.start_bake(ctx, False)
        assert op.modal(ctx, SimpleNamespace(type="ESC", value="PRESS")) == {"CANCELLED"}
        print(log)
        assert ("WARNING", "Bounce GI: bake cancelled, nothing written") in log and "timer-" in log
        import concurrent.futures
        concurrent.futures.wait([op._pending.future], timeout=300)
        same_state(before, mesh_state(meshes))

        # Polling to the end instead: the attributes appear, one INFO report.
        import time
        op, log[:] = FakeOp(), []
        op._pending = bake.start_bake(ctx, False)
        ret, deadline = {"PASS_THROUGH"}, time.time() + 300
        while ret == {"PASS_THROUGH"} and time.time() < deadline:
            time.sleep(0.02)
            ret = op.modal(ctx, SimpleNamespace(type="TIMER", value="NOTHING"))
        print(ret, [e for e in log if e[0] != "status"])
        assert ret == {"FINISHED"} and any(e[0] == "INFO" and "baked" in e[1] for e in log if isinstance(e, tuple))
        assert all(bake.ATTRIBUTE in o.data.color_attributes for o in meshes)
    """)


def test_one_undo_step_takes_the_bake_back(tmp_path):
    run_case(tmp_path, """
        scenes.build("cornell")
        scene = bpy.context.scene
        scene.bounce_gi.method, scene.bounce_gi.quality = "LPV", "DRAFT"
        names = [o.name for o in scene.objects if o.type == "MESH"]
        meshes = lambda: [bpy.data.objects[n] for n in names]  # undo reloads the data: fetch it anew
        bpy.ops.ed.undo_push(message="scene built")
        scene.frame_current = 7  # a mark of the step before the bake
        bpy.ops.ed.undo_push(message="before the bake")
        before = mesh_state(meshes())
        assert bpy.ops.bounce_gi.bake_color_attribute() == {"FINISHED"}
        bpy.ops.ed.undo_push(message="Bake GI to Color Attribute")  # what the window manager pushes (UNDO option)
        ours = baked(meshes())
        assert bpy.ops.ed.undo() == {"FINISHED"}
        assert not any(bake.ATTRIBUTE in o.data.attributes for o in meshes()), "the bake survived one undo"
        same_state(before, mesh_state(meshes()))
        assert bpy.context.scene.frame_current == 7  # the step just before the bake, not an older one
        assert bpy.ops.ed.redo() == {"FINISHED"}
        again = baked(meshes())
        assert all(np.array_equal(again[k], ours[k]) for k in ours)
        print("undo: the bake taken back in one step and redone,", sum(len(v) for v in ours.values()), "vertices")
    """)
