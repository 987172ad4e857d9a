# SPDX-License-Identifier: GPL-3.0-or-later
"""The live viewport as an installed extension runs it in background bpy: the overlay operator, depsgraph updates
from real edits turned into GI jobs (or not: a camera move re-runs nothing), the progressive stages, what the
viewport draws against F12 of the same scene, and disable/enable leaving no handler, feed or thread behind.

Background mode has no event loop, so the timers that poll the GPU thread in Blender do not run: the cases call
`session.wait()`, which polls exactly as the timer does.
"""
from tests.blender.test_render_engine import linux_zip, run_case  # noqa: F401  (the zip fixture)


def test_the_overlay_follows_edits_and_draws_what_f12_renders(linux_zip, tmp_path):
    run_case(linux_zip, tmp_path, """
        scene = open_blend(method="LPV", size=(64, 48))
        viewport, draw = ext("ui.viewport"), ext("ui.draw")
        draw.ensure_gpu()
        print("toggle", bpy.ops.bounce_gi.toggle_overlay())
        feed = viewport.newest_feed()
        assert feed is not None and ext("ui.overlay").is_on()
        session, s = feed.session, feed.session.stats
        session.wait()
        print("first", s.stage, {k: round(v, 3) for k, v in s.latency.items()}, s.main_thread, s.error)
        assert s.stage == "final" and list(s.latency) == ["direct", "draft", "final"] and not s.error
        assert s.latency["direct"] < s.latency["draft"] < s.latency["final"]

        def edit(fn):
            fn()
            bpy.context.view_layer.update()          # fires depsgraph_update_post, as an edit in the UI does
            queued = session.busy
            return queued, session.wait() or s.changed

        cam = scene.camera
        print("camera", edit(lambda: setattr(cam, "location", cam.location + type(cam.location)((0.1, 0, 0)))))
        assert not session.busy and s.changed != "camera"   # a camera move queues nothing
        before = session.drawing
        light = next(o for o in scene.objects if o.type == "LIGHT")
        queued, changed = edit(lambda: setattr(light, "location", light.location + type(light.location)((0.2, 0, 0))))
        print("light", queued, changed)
        assert queued and "light" in changed and session.drawing is not before
        mat, socket = next((m, n.inputs[name]) for m in bpy.data.materials if m.users and m.node_tree
                           for n in m.node_tree.nodes for name in ("Base Color", "Color")
                           if n.type in ("BSDF_PRINCIPLED", "BSDF_DIFFUSE") and name in n.inputs)
        queued, changed = edit(lambda: setattr(socket, "default_value", (0.9, 0.1, 0.1, 1)))
        print("material", queued, changed)
        assert queued and mat.name in changed
        obj = next(o for o in scene.objects if o.type == "MESH")
        queued, changed = edit(lambda: setattr(obj, "location", obj.location + type(obj.location)((0, 0, 0.01))))
        print("object", queued, changed)
        assert queued and obj.name in changed

        # What the viewport draws from the scene camera against F12 of the same (edited) scene.
        scene.render.filepath = os.path.join(tmp, "f12")
        bpy.ops.render.render(write_still=True)
        f12 = ext("gpu_kernels.output.exr").read_passes(os.path.join(tmp, "f12.exr"))["Combined"][..., :3]
        data = ext("addon.extract").extract_scene(bpy.context.evaluated_depsgraph_get(), resolution=(64, 48))
        light_result = ext("gpu_kernels.engine").get_engine().submit_surface(
            data, ext("ui.live").stages_for(ext("ui.preview").render_settings_of(scene.bounce_gi, 64, 48)[0])[-1][1],
            65536).result()
        shot = draw.snapshot(light_result, data, 64, 48)[..., :3]
        rel = float(np.abs(shot - f12).sum() / np.abs(f12).sum())
        print("snapshot vs F12 rel-L1", rel)
        # Measured 0.0082 here (LPV, 64x48; the indirect light on its coarser atlas): the atlas's texels against
        # pixels, at shadow edges and corners. Both paths are deterministic; the margin covers only the texel size
        # (a bisection) rounding differently on another machine.
        assert rel < 0.0102

        bpy.ops.bounce_gi.toggle_overlay()
        handlers = [h for h in bpy.app.handlers.depsgraph_update_post if "bounce" in getattr(h, "__module__", "")]
        print("off: feeds", viewport.FEEDS, "handlers", handlers)
        assert viewport.FEEDS == [] == handlers and ext("ui.overlay").state.draw_handle is None
    """, timeout=600)


def test_disable_with_the_overlay_on_leaves_nothing_behind_three_times(linux_zip, tmp_path):
    run_case(linux_zip, tmp_path, """
        scene = open_blend(size=(32, 24))
        for round_ in range(3):
            ext("ui.draw").ensure_gpu()
            bpy.ops.bounce_gi.toggle_overlay()
            feed = ext("ui.viewport").newest_feed()
            feed.session.wait()
            assert feed.session.drawing is not None and len(gpu_threads()) == 1
            overlay = ext("ui.overlay")
            bpy.ops.preferences.addon_disable(module=mod)
            handlers = [h for h in (*bpy.app.handlers.depsgraph_update_post, *bpy.app.handlers.load_pre)
                        if "bounce" in getattr(h, "__module__", "")]
            print("round", round_, "threads", gpu_threads(), "handlers", handlers, "feeds", overlay.state.feed)
            assert gpu_threads() == [] and handlers == [] and overlay.state.feed is None
            assert overlay.state.draw_handle is None and feed.session.drawing is None and feed.session.closed
            bpy.ops.preferences.addon_enable(module=mod)
    """)


def test_a_3d_view_looking_through_the_scene_camera_draws_the_camera_s_view(linux_zip, tmp_path):
    # view_draw and the overlay take their camera from the 3D view's RegionView3D (viewport.region_view); looking
    # through the scene camera, Blender's view matrix is the camera's inverse world matrix and its perspective
    # matrix is the camera's projection times it. The View must then be the snapshot's (draw.camera_view).
    run_case(linux_zip, tmp_path, """
        from mathutils import Matrix
        scene = open_blend(size=(64, 48))
        cam_data = ext("addon.extract.camera").read_camera(scene)
        cam = ext("gpu_kernels.common.camera")
        view = np.asarray(cam.view_matrix(cam_data))
        proj = np.asarray(cam.projection_matrix(cam_data, 64, 48))

        class FakeRegionView3D:
            view_matrix = Matrix(view.tolist())
            perspective_matrix = Matrix((proj @ view).tolist())
            is_perspective = True
        got = ext("ui.viewport").region_view(FakeRegionView3D())
        want = ext("ui.draw").camera_view(cam_data, 64, 48)
        print(got, want)
        assert np.allclose(got.view_projection, want.view_projection, atol=1e-5)
        assert np.allclose(got.eye, want.eye, atol=1e-5) and np.allclose(got.forward, want.forward, atol=1e-6)
        assert got.ortho == want.ortho == False
    """)


def test_the_fitted_share_draws_what_the_table_draws_in_every_display_mode(linux_zip, tmp_path):
    # The furnished room has every kind of part (ui/draw_parts.py): rough Principled materials whose share one
    # polynomial stands in for (GREY: the three channels are the same), on flat boxes and on smooth lathed
    # shapes, a glossy screen (roughness 0.1) it cannot follow within POLY_TOLERANCE, drawn from the table, metals
    # and emitters with a constant share; and, given a rough tinted coat here, walls whose share is a polynomial
    # per channel (POLY).
    # POLY_TOLERANCE = -1 draws every view-dependent share from the table: the reference.
    run_case(linux_zip, tmp_path, """
        w, h = 320, 180
        scene = open_blend(method="LPV", size=(w, h))
        walls = next(n for n in bpy.data.materials["Walls"].node_tree.nodes if n.type == "BSDF_PRINCIPLED")
        for name, value in (("Coat Weight", 0.3), ("Coat Roughness", 0.6), ("Coat Tint", (1.0, 0.6, 0.3, 1.0))):
            walls.inputs[name].default_value = value
        draw = ext("ui.draw")
        data = ext("addon.extract").extract_scene(bpy.context.evaluated_depsgraph_get(), resolution=(w, h))
        draft = ext("ui.live").stages_for(ext("ui.preview").render_settings_of(scene.bounce_gi, w, h)[0])[1][1]
        light = ext("gpu_kernels.engine").get_engine().submit_surface(data, draft, 16384).result()
        draw.ensure_gpu()
        fitted = draw.POLY_TOLERANCE
        images, variants = {}, {}
        for name, tolerance in (("poly", fitted), ("table", -1.0)):
            draw.POLY_TOLERANCE = tolerance
            drawing = draw.SurfaceDrawing(light)
            variants[name] = sorted({part[0] for part in drawing.parts})
            drawing.free()
            images[name] = {mode: draw.snapshot(light, data, w, h, mode)[..., :3]
                            for mode in ("COMBINED", "DIRECT", "INDIRECT")}
        draw.POLY_TOLERANCE = fitted
        print("variants", variants)
        assert {("grey", True), ("grey", False), ("poly", True), ("table", True), ("constant", True)} <= \
            set(variants["poly"])
        assert {share for share, _ in variants["table"]} == {"constant", "table"}
        # A pixel is share x light (+ emission, the same in both), and a polynomial is within POLY_TOLERANCE of
        # its table row at the row's samples, 1.11 times that at most between them (a sweep of 192 fitting
        # Principled inputs): so a pixel moves by at most 1.15 POLY_TOLERANCE / (the least share a polynomial
        # draws) of its value — here the coated walls' blue at grazing views, 0.62: 1.9e-3.
        parts = ext("ui.draw_parts")
        rows = parts.share_rows(draw.material_lut_of(light))
        error = ext("gpu_kernels.common.principled").share_polynomial(rows)[1]
        kinds = np.asarray(parts.SHARES)[parts.material_shares(rows, error <= fitted)]
        bound = 1.15 * fitted / rows[np.isin(kinds, ["grey", "poly"]), :, :3].min()
        for mode, table in images["table"].items():
            diff = np.abs(images["poly"][mode] - table)
            rel = diff / np.maximum(table, 1e-4)
            print(mode, f"max {diff.max():.2e} max relative {rel.max():.2e} (bound {bound:.2e}) "
                  f"rel-L1 {diff.sum() / table.sum():.2e}")
            assert table.max() > 0.01     # lit, in every mode
            # Over the image the fits stray by 2-7e-4 of shares of 0.6-0.95 (most strays at grazing views, on
            # few pixels): measured rel-L1 3.4e-5 (Combined), the other modes alike; 2e-4 leaves room for
            # another camera or light, not for a fit drawn wrong (measured: the red channel's polynomial drawn
            # for all three, 2.7e-2; t = 1 − 2μ, 7.0e-2).
            assert rel.max() <= bound and diff.sum() / table.sum() <= 2e-4
    """, env={"CASE_SCENE": "furnished"}, timeout=600)
