# SPDX-License-Identifier: GPL-3.0-or-later
"""The live viewport's costs per example scene, in background bpy with the extension's own modules:

  - latency from an edit (light move, material colour, object move) to each stage uploaded (direct light,
    draft GI, final GI), as ui/live.py's stats record it: what a user waits for after the edit;
  - main-thread time per update: the depsgraph handler (change set + extraction) and the upload of each stage;
  - redraw cost at 960×540: our surface shader drawing a result, against Blender's builtin flat shader drawing
    the same triangles (what Blender's own Solid drawing of those meshes costs at least), each timed with a
    read-back so the GPU work is inside the measurement;
  - F12 (the render engine, the scene camera, 160×120), with every pass run and again with the cache holding.

    .venv/bin/python benchmarks/viewport_bench.py [--method lpv|vct|none] [--scenes cornell spot_room courtyard]

Prints one table per scene and asserts nothing; results/viewport_llvmpipe.md holds a run on the 2-core dev box.
"""
import argparse
import os
import statistics
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)  # examples/


def timed_draws(fn, offscreen, repeats=7):
    """Median seconds of fn() into `offscreen` with a 1-pixel read-back (so the GPU finished)."""
    import gpu

    out = []
    for _ in range(repeats + 1):
        start = time.perf_counter()
        with offscreen.bind():
            fn()
            gpu.state.active_framebuffer_get().read_color(0, 0, 1, 1, 4, 0, "FLOAT")
        out.append(time.perf_counter() - start)
    return statistics.median(out[1:])


def redraw_costs(drawing, positions, world) -> tuple[float, float]:
    """(ours, Blender's flat builtin shader) seconds to draw the same triangles at 960×540 from the scene camera."""
    import bpy
    import gpu
    from gpu_extras.batch import batch_for_shader
    from mathutils import Matrix

    from bounce_gi.addon.extract.camera import read_camera
    from bounce_gi.ui import draw

    w, h = 960, 540
    offscreen = gpu.types.GPUOffScreen(w, h, format="RGBA16F")
    view = draw.camera_view(read_camera(bpy.context.scene), w, h)
    ours = timed_draws(lambda: draw.draw_offscreen(drawing, offscreen, view, world), offscreen)
    flat = gpu.shader.from_builtin("UNIFORM_COLOR")
    batch = batch_for_shader(flat, "TRIS", {"pos": positions})

    def plain():
        gpu.state.active_framebuffer_get().clear(color=(0, 0, 0, 1), depth=1.0)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.matrix.load_matrix(Matrix.Identity(4))
        gpu.matrix.load_projection_matrix(Matrix(view.view_projection.tolist()))
        flat.bind()
        flat.uniform_float("color", (0.8, 0.8, 0.8, 1.0))
        batch.draw(flat)
        gpu.state.depth_test_set("NONE")
    base = timed_draws(plain, offscreen)
    offscreen.free()
    return ours, base


def bench_scene(name: str, method: str) -> dict:
    import bpy

    from bounce_gi.ui import draw
    from bounce_gi.ui.viewport import ViewportFeed
    from examples import scenes

    path = os.path.join(tempfile.mkdtemp(), f"{name}.blend")
    scenes.save(name, path)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    scene.bounce_gi.method = method.upper()
    draw.ensure_gpu()
    feed = ViewportFeed()
    handler_times = []

    def on_update(_scene, depsgraph):
        start = time.perf_counter()
        feed.update(depsgraph)
        handler_times.append(time.perf_counter() - start)
    bpy.app.handlers.depsgraph_update_post.append(on_update)
    rows = {}
    start = time.perf_counter()
    feed.update(bpy.context.evaluated_depsgraph_get(), first=True)
    handler_times.append(time.perf_counter() - start)
    rows["open"] = run_stages(feed, handler_times)

    light = next(o for o in scene.objects if o.type == "LIGHT")
    mat, socket = next((m, n.inputs[k]) for m in bpy.data.materials if m.users and m.node_tree
                       for n in m.node_tree.nodes for k in ("Base Color", "Color")
                       if n.type in ("BSDF_PRINCIPLED", "BSDF_DIFFUSE") and k in n.inputs)
    meshes = [o for o in scene.objects if o.type == "MESH"]
    obj = next((o for o in meshes if o.name != "Floor"), meshes[0])
    edits = {"light move": lambda: light.location.__setitem__(0, light.location[0] + 0.1),
             "material colour": lambda: setattr(socket, "default_value", (0.7, 0.3, 0.2, 1.0)),
             "object move": lambda: obj.location.__setitem__(2, obj.location[2] + 0.01)}
    for label, edit in edits.items():
        handler_times.clear()
        edit()
        bpy.context.view_layer.update()
        rows[label] = run_stages(feed, handler_times)
    bpy.app.handlers.depsgraph_update_post.remove(on_update)
    ours, base = redraw_costs(feed.session.drawing, _positions(), feed.world_color)
    scene.render.engine = "BOUNCE_GI"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 160, 120, 100
    from bounce_gi.gpu_kernels.engine import get_engine

    f12 = {}
    for label, clear in (("cold", True), ("again", False)):  # cold: every pass runs; again: the cache holds
        if clear:
            get_engine().clear_cache()
        start = time.perf_counter()
        bpy.ops.render.render(write_still=False)
        f12[label] = time.perf_counter() - start
    feed.close()
    return {"rows": rows, "redraw": (ours, base), "f12": f12, "texels": feed.session.stats.texels}


def _positions():
    import bpy

    from bounce_gi.addon.extract import extract_scene

    data = extract_scene(bpy.context.evaluated_depsgraph_get(), (64, 64), require_camera=False)
    return np.asarray(data.positions, np.float32).reshape(-1, 3)


def run_stages(feed, handler_times) -> dict:
    session = feed.session
    uploads = []
    while session.busy:
        before = session.stats.main_thread.get("upload")
        session.poll()
        after = session.stats.main_thread.get("upload")
        if after is not before and after is not None:
            uploads.append(after)
        time.sleep(0.005)
    s = session.stats
    return {"latency": dict(s.latency), "handler": max(handler_times) if handler_times else 0.0,
            "upload": max(uploads) if uploads else 0.0, "changed": s.changed, "error": s.error}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--method", default="lpv", choices=("none", "lpv", "vct"))
    p.add_argument("--scenes", nargs="+", default=["cornell", "spot_room", "courtyard"])
    args = p.parse_args(argv)
    import bounce_gi

    bounce_gi.register()  # the scene settings, as the enabled extension has them
    for name in args.scenes:
        r = bench_scene(name, args.method)
        ours, base = r["redraw"]
        print(f"\n## {name} ({args.method}, {r['texels']} texels)")
        print(f"{'edit':<17}{'direct':>9}{'draft':>9}{'final':>9}{'handler':>10}{'upload':>9}   changed")
        for label, row in r["rows"].items():
            lat = row["latency"]
            cells = "".join(f"{lat[k]:>8.2f}s" if k in lat else f"{'-':>9}" for k in ("direct", "draft", "final"))
            print(f"{label:<17}{cells}{row['handler'] * 1000:>8.1f}ms{row['upload'] * 1000:>7.1f}ms   "
                  f"{row['changed']}{'  ERROR ' + row['error'] if row['error'] else ''}")
        print(f"redraw 960x540: ours {ours * 1000:.2f} ms, builtin flat shader {base * 1000:.2f} ms, "
              f"difference {(ours - base) * 1000:.2f} ms")
        print(f"F12 160x120: {r['f12']['cold']:.2f} s with every pass run, {r['f12']['again']:.2f} s again")


if __name__ == "__main__":
    main()
