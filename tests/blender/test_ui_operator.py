# SPDX-License-Identifier: GPL-3.0-or-later
"""The preview operator's steps in background Blender: image writing, panel drawing, and a real
render of a tiny scene (cube + sun + camera) through addon.extract and the gpu_kernels engine.

Modal operators never run in background mode, so the operator's execute() (blocking) and the plain
functions in ui/preview.py are what is exercised; invoke()/modal() only schedule those same steps.
Each case runs in its own subprocess (bpy state must not leak) and prints what it sees.
"""
import os
import subprocess
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# Prepended to every case: `bounce_gi` is this checkout, its UI registered.
PRELUDE = """
import sys
import bpy
import numpy as np
import bounce_gi
from bounce_gi.ui import preview
bounce_gi.register()
"""


def run_case(tmp_path, body: str, setup: str = "", timeout: float = 180) -> str:
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    os.symlink(ROOT, pkg / "bounce_gi")  # import this checkout whether or not it is pip-installed
    code = PRELUDE + setup + textwrap.dedent(body) + "\nprint('CASE OK')\n"
    env = {**os.environ, "PYTHONPATH": str(pkg), "BLENDER_USER_RESOURCES": str(tmp_path / "user")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout,
                          cwd=ROOT, env=env)
    output = f"--- exit status {proc.returncode}\n--- stdout\n{proc.stdout}\n--- stderr\n{proc.stderr}"
    assert proc.returncode == 0 and "CASE OK" in proc.stdout, output
    return proc.stdout


def test_write_preview_image_orientation_and_reuse(tmp_path):
    run_case(tmp_path, """
        a = np.zeros((3, 5, 4), np.float32)
        a[0, :, 0] = 2.5          # top row red, above 1: float buffer must keep it
        a[..., 3] = 1.0
        img = preview.write_preview_image(a)
        px = np.empty(5 * 3 * 4, np.float32); img.pixels.foreach_get(px); px = px.reshape(3, 5, 4)
        print("size", tuple(img.size), "float", img.is_float, "colorspace", img.colorspace_settings.name)
        assert img.name == "Bounce GI Preview" and tuple(img.size) == (5, 3) and img.is_float
        assert img.colorspace_settings.name != "sRGB"
        assert np.allclose(px[2, :, 0], 2.5) and np.allclose(px[0, :, 0], 0.0), px[..., 0]  # Blender: bottom-up

        # A new size reuses the same datablock; RGB input gets alpha 1.
        img2 = preview.write_preview_image(np.full((2, 4, 3), 0.25, np.float32))
        px = np.empty(4 * 2 * 4, np.float32); img2.pixels.foreach_get(px)
        print("resized", tuple(img2.size), "images", [i.name for i in bpy.data.images])
        assert img2 == img and tuple(img2.size) == (4, 2) and np.allclose(px.reshape(-1, 4), [0.25, 0.25, 0.25, 1])

        # A byte image (sRGB) of the same name is kept aside, never overwritten.
        img.name = "other"
        bpy.data.images.new("Bounce GI Preview", 2, 2)
        img3 = preview.write_preview_image(np.ones((2, 2, 4), np.float32))
        print("images", sorted(i.name for i in bpy.data.images))
        assert img3.is_float and "Bounce GI Preview (old)" in bpy.data.images

        try:
            preview.write_preview_image(np.ones((4, 4), np.float32))
        except preview.PreviewError as ex:
            print("bad shape:", ex)
        else:
            raise AssertionError("a 2-D Combined pass was accepted")
    """)


# No UI in background mode, so draw() gets a recording layout that checks every property, operator and icon name
# against Blender's RNA (typos there only show up as console errors); `seen` records what was drawn.
RECORDING_LAYOUT = """
from types import SimpleNamespace
from bounce_gi.ui import panel
icons = set(bpy.types.UILayout.bl_rna.functions["label"].parameters["icon"].enum_items.keys())
seen = []

class Layout:
    def __getattr__(self, name):   # row(), column(), box(), split() ...
        return lambda *a, **k: Layout()
    def __setattr__(self, name, value):
        pass
    def prop(self, data, name, **k):
        assert name in data.bl_rna.properties, name; seen.append(("prop", name))
    def operator(self, idname, **k):
        mod, op = idname.split(".")
        getattr(getattr(bpy.ops, mod), op).get_rna_type(); seen.append(("op", idname))
        assert k.get("icon", "NONE") in icons, k
    def label(self, text="", icon="NONE", **k):
        assert icon in icons, icon; seen.append(("label", text))
"""


def test_panels_draw_with_valid_names(tmp_path):
    run_case(tmp_path, RECORDING_LAYOUT + """
        ctx = SimpleNamespace(scene=bpy.context.scene)
        preview.state.last = preview.RenderReport("none", 32, 24, {"gbuffer": 0.002, "shadow_maps": 0.0,
                                                  "total": 0.01}, ["material 'X' fell back"], 0.5, ["shadow_maps"])
        preview.state.last_error = "an error"
        for busy in (False, True):
            preview.state.busy = busy
            panel.VIEW3D_PT_bounce_gi.draw(SimpleNamespace(layout=Layout()), ctx)
        assert panel.VIEW3D_PT_bounce_gi_last_render.poll(ctx)
        panel.VIEW3D_PT_bounce_gi_last_render.draw(SimpleNamespace(layout=Layout()), ctx)
        print(seen)
        assert ("label", "cached") in seen and ("label", "material 'X' fell back") in seen
        assert {("prop", "method"), ("prop", "resolution_percentage"), ("prop", "output_path")} <= set(seen)

        # Render Properties, with Bounce GI as the engine: the same settings, not the preview's size or Output.
        seen.clear()
        assert panel.RENDER_PT_bounce_gi.poll(SimpleNamespace(engine="BOUNCE_GI"))
        assert not panel.RENDER_PT_bounce_gi.poll(SimpleNamespace(engine="CYCLES"))
        bpy.context.scene.bounce_gi.use_time_budget = True
        panel.RENDER_PT_bounce_gi.draw(SimpleNamespace(layout=Layout()), ctx)
        print("render properties", seen)
        assert seen == [("prop", "use_time_budget"), ("prop", "time_budget_ms"), ("prop", "method"),
                        ("prop", "quality"), ("prop", "display_mode")], seen
        bpy.context.scene.bounce_gi.use_time_budget = False
        seen.clear()
        bpy.context.scene.bounce_gi.method = "LPV"   # a method by hand: its advanced overrides show
        panel.RENDER_PT_bounce_gi.draw(SimpleNamespace(layout=Layout()), ctx)
        assert seen == [("prop", "use_time_budget"), ("prop", "method"), ("prop", "quality"), ("prop", "bounces"),
                        ("prop", "grid_resolution"), ("prop", "display_mode")], seen


        # Opening another file forgets the last render (its times would describe another scene).
        bpy.ops.wm.read_homefile(use_empty=True)
        print("after load:", preview.state.last, preview.state.last_error)
        assert preview.state.last is None and preview.state.last_error is None
        assert not panel.VIEW3D_PT_bounce_gi_last_render.poll(ctx)
    """)


def test_compare_panel_draws_the_last_report(tmp_path):
    run_case(tmp_path, RECORDING_LAYOUT + """
        from bounce_gi.ui import compare
        ctx = SimpleNamespace(scene=bpy.context.scene)
        compare.state.last = {"method": "lpv", "resolution": [32, 24], "reference": {"samples": 16},
                              "rel_l1": {"combined": 0.12, "diffuse_direct": 0.026, "diffuse_indirect": 0.25},
                              "noise_floor": {"combined": 0.1, "diffuse_direct": 0.003, "diffuse_indirect": 0.22},
                              "rel_mse": 0.01, "diffuse_color_match": 0.99,
                              "seconds": {"ours": 2.1, "cycles": 0.7, "cycles_cached": False}, "warnings": ["w1"]}
        for busy in (False, True):
            compare.state.busy, compare.state.status = busy, "Cycles reference: seed 1" if busy else ""
            panel.VIEW3D_PT_bounce_gi_compare.draw(SimpleNamespace(layout=Layout()), ctx)
        print(seen)
        assert ("op", "bounce_gi.compare_cycles") in seen and ("prop", "compare_samples") in seen
        assert {("label", "Diffuse Indirect"), ("label", "0.250"), ("label", "0.220"), ("label", "w1"),
                ("label", "Cycles reference: seed 1")} <= set(seen)
        compare.state.busy = False
        bpy.ops.wm.read_homefile(use_empty=True)   # another file: its errors would mislead
        assert compare.state.last is None
    """)


TINY_SCENE = """
for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob)
scene = bpy.context.scene
bpy.ops.mesh.primitive_cube_add(size=2.0)
sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (0.6, 0.2, 0.3)
scene.collection.objects.link(sun)
cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
cam.location = (6.0, -6.0, 4.5)
cam.rotation_euler = (1.1, 0.0, 0.785)
scene.collection.objects.link(cam)
scene.camera = cam
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
scene.bounce_gi.resolution_percentage = 50
"""


def test_render_preview_end_to_end(tmp_path):
    out = run_case(tmp_path, setup=TINY_SCENE, body="""
        # The operator's blocking path (what a script or background job gets).
        print("operator", bpy.ops.bounce_gi.render_preview())
        img = bpy.data.images["Bounce GI Preview"]
        px = np.empty(img.size[0] * img.size[1] * 4, np.float32); img.pixels.foreach_get(px)
        last = preview.state.last
        print("image", tuple(img.size), "max", px.max(), "timings", last.timings, "warnings", last.warnings)
        assert tuple(img.size) == (32, 24)            # 64x48 at 100 %, preview at 50 %
        assert np.isfinite(px).all() and px.reshape(-1, 4)[:, :3].max() > 0.0  # the lit cube shows
        assert "total" in last.timings and (last.width, last.height) == (32, 24)

        # The same steps as plain functions (what invoke/modal schedule), at another size.
        scene.bounce_gi.resolution_percentage = 25
        pending = preview.start_render(scene, bpy.context.evaluated_depsgraph_get())
        report = preview.finish_render(pending, timeout=120)
        print("plain", report.width, report.height, tuple(img.size))
        assert tuple(img.size) == (16, 12) and (report.width, report.height) == (16, 12)

        # A time budget picks the method from the committed quality table: with an unlimited budget, the most
        # accurate entry; the panel's report says what was chosen.
        from bounce_gi.addon.quality import load_table
        best = min(load_table()["entries"], key=lambda e: e["rel_l1"])
        scene.bounce_gi.use_time_budget, scene.bounce_gi.time_budget_ms = True, 1e9
        report = preview.finish_render(preview.start_render(scene, bpy.context.evaluated_depsgraph_get()), 300)
        print("budget", report.method, report.quality)
        assert report.method == best["method"] and report.quality.startswith("chose " + best["label"])
    """)
    assert "CASE OK" in out


def test_errors_are_one_line_reports(tmp_path):
    run_case(tmp_path, setup=TINY_SCENE, body="""
        def op_error():
            try:
                bpy.ops.bounce_gi.render_preview()
            except RuntimeError as ex:   # how bpy.ops surfaces self.report({'ERROR'}) + CANCELLED
                return str(ex)
            raise AssertionError("the operator did not report an error")

        scene.camera = None
        msg = op_error(); print("no camera:", msg)
        assert "camera" in msg.lower() and "Traceback" not in msg and msg.count("\\n") <= 1
        assert preview.state.busy is False
    """)


def test_modal_path_with_simulated_events(tmp_path):
    # invoke()/modal() need a window, which background mode lacks; drive them with stand-ins for
    # context, window manager and events. The class's methods are plain functions, so a stand-in
    # `self` borrows them (a bpy Operator cannot be instantiated outside an operator call).
    run_case(tmp_path, setup=TINY_SCENE, body="""
        import time
        from types import SimpleNamespace
        from bounce_gi.ui.operators import BOUNCE_GI_OT_render_preview as Op

        log = []
        class WM:
            windows = []
            def event_timer_add(self, step, window=None): log.append("timer+"); return "timer"
            def event_timer_remove(self, timer): log.append("timer-")
            def modal_handler_add(self, op): log.append("handler")
        class Workspace:
            def status_text_set(self, text): log.append(("status", text))
        class FakeOp:
            invoke, modal, cancel, _fail, _progress, _cleanup = Op.invoke, Op.modal, Op.cancel, Op._fail, \\
                Op._progress, Op._cleanup
            _pending = None
            def report(self, kind, msg): log.append((sorted(kind)[0], msg))
        ctx = SimpleNamespace(scene=scene, window=None, window_manager=WM(), workspace=Workspace(),
                              evaluated_depsgraph_get=bpy.context.evaluated_depsgraph_get)
        timer, esc = SimpleNamespace(type="TIMER", value="NOTHING"), SimpleNamespace(type="ESC", value="PRESS")

        op = FakeOp()
        assert op.invoke(ctx, None) == {"RUNNING_MODAL"} and preview.state.busy
        assert not Op.poll(bpy.context)   # a second preview cannot start meanwhile
        deadline, ret = time.time() + 120, {"PASS_THROUGH"}
        while ret == {"PASS_THROUGH"} and time.time() < deadline:
            time.sleep(0.02)
            ret = op.modal(ctx, timer)
        print(ret, log)
        assert ret == {"FINISHED"} and not preview.state.busy and preview.state.timer is None
        assert log.count("timer+") == log.count("timer-") == 1 and ("status", None) in log[log.index("timer-"):]
        assert any(kind == "INFO" for kind, *_ in log if isinstance(kind, str) and kind.isupper())
        assert tuple(bpy.data.images["Bounce GI Preview"].size) == (32, 24)

        # Esc stops waiting: timer removed, status cleared, the operator cancelled.
        log.clear()
        op = FakeOp()
        assert op.invoke(ctx, None) == {"RUNNING_MODAL"}
        assert op.modal(ctx, esc) == {"CANCELLED"} and not preview.state.busy
        print(log)
        assert "timer-" in log and ("status", None) in log and preview.state.last_error == "Cancelled"
        import concurrent.futures   # cancelled if still queued, else let it finish before exiting
        concurrent.futures.wait([op._pending.future], timeout=120)
    """)


def test_output_setting_writes_the_passes(tmp_path):
    """The panel's Output setting: the preview's passes land in that multi-layer EXR (Combined equal to the
    preview image, every pass written); a folder or a non-EXR name is one error line and writes nothing."""
    out = tmp_path / "renders" / "preview"  # no extension: .exr is added; the folder is created
    run_case(tmp_path, setup=TINY_SCENE, body=f"""
        import os
        from bounce_gi.gpu_kernels.compose import PASS_NAMES
        from bounce_gi.gpu_kernels.output.exr import read_passes
        scene.bounce_gi.output_path = {str(out)!r}
        print("operator", bpy.ops.bounce_gi.render_preview())
        passes = read_passes({str(out) + ".exr"!r})
        img = bpy.data.images["Bounce GI Preview"]
        px = np.empty(img.size[0] * img.size[1] * 4, np.float32); img.pixels.foreach_get(px)
        px = px.reshape(img.size[1], img.size[0], 4)[::-1]  # Blender's rows are bottom-up
        print("passes", sorted(passes), "combined", passes["Combined"].shape)
        assert set(PASS_NAMES) <= set(passes)
        assert np.array_equal(passes["Combined"][..., :3], px[..., :3])  # the same float32 values, not a copy
        for bad in ({str(tmp_path)!r}, {str(tmp_path / "x.png")!r}):
            scene.bounce_gi.output_path = bad
            try:
                bpy.ops.bounce_gi.render_preview()
            except RuntimeError as ex:
                print("bad output:", ex)
                assert "Output" in str(ex) and str(ex).count("\\n") <= 1
            else:
                raise AssertionError(f"Output {{bad}} was accepted")
        assert not os.path.exists({str(tmp_path / "x.png")!r})
    """)


def test_the_viewport_panel_shows_the_live_stats(tmp_path):
    run_case(tmp_path, RECORDING_LAYOUT + """
        ctx = SimpleNamespace(scene=bpy.context.scene)
        from bounce_gi.ui import viewport
        assert not panel.VIEW3D_PT_bounce_gi_viewport.poll(ctx)
        feed = viewport.ViewportFeed()
        st = feed.session.stats
        st.stage, st.running, st.latency = "draft", "final", {"direct": 0.1, "draft": 1.2}
        st.main_thread, st.timings, st.skipped = {"extract": 0.004}, {"rsm": 0.1, "gbuffer": 0.0}, ["gbuffer"]
        st.texels, st.triangles, st.lights, st.grid = 1000, 12, {"AREA": 1}, "32 x 32 x 32"
        seen.clear()
        assert panel.VIEW3D_PT_bounce_gi_viewport.poll(ctx)
        panel.VIEW3D_PT_bounce_gi_viewport.draw(SimpleNamespace(layout=Layout()), ctx)
        print("viewport panel", seen)
        assert ("label", "draft GI (computing final)") in seen and ("label", "Edit → draft") in seen
        assert ("label", "cached") in seen and ("label", "Lights: 1 area") in seen
        assert ("label", "Grid: 32 x 32 x 32") in seen
        feed.close()
        assert not panel.VIEW3D_PT_bounce_gi_viewport.poll(ctx)
    """)


def test_the_live_session_keeps_one_job_and_replaces_the_queued_one(tmp_path):
    # ui/live.py with a fake engine (Futures resolved by hand) and a fake upload: what is submitted, in which
    # order, and what the stats say — the behaviour the viewport relies on, independent of any GPU.
    run_case(tmp_path, """
        from concurrent.futures import Future
        from types import SimpleNamespace
        from bounce_gi.ui import live
        from bounce_gi.gpu_kernels.settings import RenderSettings

        submitted = []
        def submit(scene, settings, texels):
            f = Future(); submitted.append((scene, settings.method, texels, f)); return f
        drawings = []
        def light():
            return SimpleNamespace(atlas=SimpleNamespace(texel_count=10, texel=0.1), timings={"total": 0.1},
                                   skipped=[], warnings=[], statistics={"lights": {"SUN": 1, "AREA": 0}},
                                   info={"grid": [32, 32, 16]})
        s = live.LiveSession(submit=submit, make_drawing=lambda l: drawings.append(l) or SimpleNamespace(
            triangles=2, free=lambda: None))
        lpv = RenderSettings("lpv", 8, 8)
        assert [n for n, *_ in live.stages_for(lpv)] == ["direct", "draft", "final"]
        assert [n for n, *_ in live.stages_for(RenderSettings("none", 8, 8))] == ["direct", "final"]
        draft = live.stages_for(lpv)[1][1]
        assert draft.lpv.resolution == 16 and live.stages_for(lpv)[2][1] == lpv

        s.request("A", lpv)
        s.request("B", lpv)
        s.request("C", lpv)                      # B never starts: C replaced it
        assert [x[:3] for x in submitted] == [("A", "none", 16384)] and s.queued[0] == "C"
        assert s.poll() is not None              # A's first stage still running
        submitted[0][3].set_result(light())
        assert s.poll() is not None              # shown, and the queued C starts over (A's other stages dropped)
        assert s.stats.stage == "direct" and len(drawings) == 1 and s.stats.lights == {"SUN": 1}
        assert s.stats.grid == "32 x 32 x 16"
        assert [x[:3] for x in submitted[1:]] == [("C", "none", 16384)]
        for expected in (("C", "lpv", 16384), ("C", "lpv", 65536)):
            submitted[-1][3].set_result(light())
            s.poll()
            assert submitted[-1][:3] == expected, submitted[-1][:3]
        submitted[-1][3].set_exception(RuntimeError("boom"))
        assert s.poll() is None and not s.busy
        print(s.stats)
        assert s.stats.error == "boom" and s.stats.stage == "draft" and list(s.stats.latency) == ["direct", "draft"]
        s.close()
        assert s.drawing is None and s.poll() is None
    """)
