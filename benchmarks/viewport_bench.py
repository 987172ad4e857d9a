# SPDX-License-Identifier: GPL-3.0-or-later
"""The live viewport's costs per example scene, in background bpy with the extension's own modules:

  - latency from an edit (light move, material colour, object move) to each stage uploaded (direct light,
    draft GI, final GI), as ui/live.py's stats record it: what a user waits for after the edit;
  - main-thread time per update: the depsgraph handler (change set + extraction) and the upload of each stage;
  - redraw cost at 960×540 (and any --res): Rendered shading's redraw of the final result from the scene camera
    (draw.draw_view3d, what view_draw does, into an RGBA16F framebuffer like the 3D view's), against Blender's
    builtin flat shader drawing the same triangles into the same framebuffer (what Blender's own Solid drawing of
    those meshes costs at least). The two alternate, round after round, so a load that comes and goes on the
    machine falls on both; each redraw is timed up to a 1-pixel read-back, which waits for the GL to finish (on
    llvmpipe a draw call only queues the work); the medians of 60 rounds after 5 of warm-up, and the median of
    the rounds' differences; with them how many cores other processes kept busy meanwhile (/proc/stat's busy
    time less this process's own CPU time): llvmpipe's times double when another process holds one of 2 cores,
    so a reading above LOADED_CORES flags the line;
  - F12 (the render engine, the scene camera, 160×120), with every pass run and again with the cache holding.

    .venv/bin/python benchmarks/viewport_bench.py [--method lpv|vct|none] [--scenes cornell spot_room courtyard]
        [--res W H ...] [--redraw-only]

--redraw-only computes the final stage once and times only the redraws. Prints one table per scene and asserts
nothing; results/viewport_llvmpipe.md holds runs on the 2-core dev box.
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


# Cores other processes may keep busy, on average, before a redraw line is flagged as measured under load (a
# desktop's idle background stays under a tenth of a core).
LOADED_CORES = 0.2


def cpu_sample():
    """(seconds all cores spent busy since boot, this process's CPU seconds, wall-clock seconds), or None where
    /proc/stat is missing (not Linux). Busy is all but idle and iowait; steal counts too: a virtual machine's
    core taken by the host is as lost to llvmpipe as one taken by a process."""
    try:
        with open("/proc/stat") as f:
            ticks = [int(x) for x in f.readline().split()[1:9]]
    except (OSError, ValueError):
        return None
    t = os.times()  # all this process's threads, llvmpipe's included
    return (sum(ticks) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK"), t.user + t.system, time.perf_counter()


def others_busy(before, after):
    """Cores other processes kept busy on average between two cpu_samples (None if either is None)."""
    if before is None or after is None:
        return None
    busy, own, wall = (b - a for a, b in zip(before, after))
    return max(0.0, (busy - own) / wall) if wall > 0 else None


def timed_rounds(draws: dict, target, rounds=60, warm_up=5) -> dict:
    """name → seconds of each of `rounds` redraws into `target`, the draws alternating round after round, each
    timed up to a 1-pixel read-back (so the GL finished)."""
    import gpu

    times = {name: [] for name in draws}
    for r in range(warm_up + rounds):
        for name, fn in draws.items():
            start = time.perf_counter()
            with target.bind():
                fn()
                gpu.state.active_framebuffer_get().read_color(0, 0, 1, 1, 4, 0, "FLOAT")
            if r >= warm_up:
                times[name].append(time.perf_counter() - start)
    return times


def flat_draw(positions, view):
    """Blender's builtin UNIFORM_COLOR shader drawing `positions` (triangles) depth-tested and depth-writing, after
    the same clear as ours."""
    import gpu
    from gpu_extras.batch import batch_for_shader
    from mathutils import Matrix

    flat = gpu.shader.from_builtin("UNIFORM_COLOR")
    batch = batch_for_shader(flat, "TRIS", {"pos": positions})

    def plain():
        gpu.state.active_framebuffer_get().clear(color=(0, 0, 0, 1), depth=1.0)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        gpu.matrix.load_matrix(Matrix.Identity(4))
        gpu.matrix.load_projection_matrix(Matrix(view.view_projection.tolist()))
        flat.bind()
        flat.uniform_float("color", (0.8, 0.8, 0.8, 1.0))
        batch.draw(flat)
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)
    return plain


def redraw_costs(drawing, positions, world, sizes) -> dict:
    """(w, h) → (ours, flat, median of the rounds' differences in seconds, cores others kept busy meanwhile):
    Rendered shading's redraw and Blender's flat builtin shader drawing the same triangles, from the scene
    camera."""
    import bpy
    import gpu

    from bounce_gi.addon.extract.camera import read_camera
    from bounce_gi.ui import draw

    out = {}
    for w, h in sizes:
        target = gpu.types.GPUOffScreen(w, h, format="RGBA16F")  # the 3D view's colour buffer is RGBA16F too
        view = draw.camera_view(read_camera(bpy.context.scene), w, h)
        before = cpu_sample()
        times = timed_rounds({"ours": lambda: draw.draw_view3d(drawing, view, world),
                              "flat": flat_draw(positions, view)}, target)
        load = others_busy(before, cpu_sample())
        target.free()
        diff = [a - b for a, b in zip(times["ours"], times["flat"])]
        out[(w, h)] = (statistics.median(times["ours"]), statistics.median(times["flat"]), statistics.median(diff),
                       load)
    return out


def mode_switch_costs(drawing, world, size) -> dict:
    """Display mode → seconds of its first redraw at `size` (up to a 1-pixel read-back), after the viewport's timer
    has run draw.compile_next_shader until nothing is left, as it does after a result is shown: the main thread's
    stall when the user first switches to that mode."""
    import bpy
    import gpu

    from bounce_gi.addon.extract.camera import read_camera
    from bounce_gi.ui import draw

    while draw.compile_next_shader(drawing):
        pass
    w, h = size
    target = gpu.types.GPUOffScreen(w, h, format="RGBA16F")
    view = draw.camera_view(read_camera(bpy.context.scene), w, h)
    out = {}
    for mode in (m for m in draw.MODES if m != "COMBINED"):
        start = time.perf_counter()
        with target.bind():
            draw.draw_view3d(drawing, view, world, mode)
            gpu.state.active_framebuffer_get().read_color(0, 0, 1, 1, 4, 0, "FLOAT")
        out[mode] = time.perf_counter() - start
    target.free()
    return out


def open_scene(name: str, method: str):
    """Build example scene `name`, open it as a .blend (as a user would), set the method; bpy's gpu ready."""
    import bpy

    from bounce_gi.ui import draw
    from examples import scenes

    path = os.path.join(tempfile.mkdtemp(), f"{name}.blend")
    scenes.save(name, path)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    scene.bounce_gi.method = method.upper()
    draw.ensure_gpu()
    return scene


def edit_latencies(feed, scene) -> dict:
    """label → run_stages' row: the scene opened, then a light move, a material colour and an object move."""
    import bpy

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
    return rows


def f12_times(scene) -> dict:
    """F12 at 160×120: "cold" with every pass run, "again" with the pass cache holding."""
    import bpy

    from bounce_gi.gpu_kernels.engine import get_engine

    scene.render.engine = "BOUNCE_GI"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 160, 120, 100
    f12 = {}
    for label, clear in (("cold", True), ("again", False)):
        if clear:
            get_engine().clear_cache()
        start = time.perf_counter()
        bpy.ops.render.render(write_still=False)
        f12[label] = time.perf_counter() - start
    return f12


def bench_scene(name: str, method: str, sizes, redraw_only=False) -> dict:
    import bpy

    from bounce_gi.ui.viewport import ViewportFeed

    scene = open_scene(name, method)
    feed = ViewportFeed()
    if redraw_only:
        feed.update(bpy.context.evaluated_depsgraph_get(), first=True)
        feed.session.wait()
        rows = {}
    else:
        rows = edit_latencies(feed, scene)
    redraw = redraw_costs(feed.session.drawing, _positions(), feed.world_color, sizes)
    switch = mode_switch_costs(feed.session.drawing, feed.world_color, sizes[0])
    f12 = None if redraw_only else f12_times(scene)
    stats = feed.session.stats
    feed.close()
    return {"rows": rows, "redraw": redraw, "switch": switch, "f12": f12, "texels": stats.texels,
            "triangles": stats.triangles}


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


def print_scene(name: str, method: str, r: dict) -> None:
    print(f"\n## {name} ({method}, {r['texels']} texels, {r['triangles']} triangles)")
    if r["rows"]:
        print(f"{'edit':<17}{'direct':>9}{'draft':>9}{'final':>9}{'handler':>10}{'upload':>9}   changed")
    for label, row in r["rows"].items():
        lat = row["latency"]
        cells = "".join(f"{lat[k]:>8.2f}s" if k in lat else f"{'-':>9}" for k in ("direct", "draft", "final"))
        print(f"{label:<17}{cells}{row['handler'] * 1000:>8.1f}ms{row['upload'] * 1000:>7.1f}ms   "
              f"{row['changed']}{'  ERROR ' + row['error'] if row['error'] else ''}")
    for (w, h), (ours, flat, diff, load) in r["redraw"].items():
        print(f"redraw {w}x{h}: ours {ours * 1000:.2f} ms, builtin flat shader {flat * 1000:.2f} ms, "
              f"difference {diff * 1000:.2f} ms; {load_note(load)}")
    print("first redraw after a switch of display mode: " +
          ", ".join(f"{mode.lower()} {t * 1000:.1f} ms" for mode, t in r["switch"].items()))
    if r["f12"]:
        print(f"F12 160x120: {r['f12']['cold']:.2f} s with every pass run, {r['f12']['again']:.2f} s again")


def load_note(load) -> str:
    """What the redraw line says of the other processes' load during its rounds."""
    if load is None:
        return "other processes' load unknown (no /proc/stat)"
    flag = f" — LOADED (over {LOADED_CORES}): llvmpipe's times are inflated" if load > LOADED_CORES else ""
    return f"other processes kept {load:.2f} of {os.cpu_count()} cores busy{flag}"


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--method", default="lpv", choices=("none", "lpv", "vct"))
    p.add_argument("--scenes", nargs="+", default=["cornell", "spot_room", "courtyard"])
    p.add_argument("--res", nargs="+", type=int, default=[960, 540], help="redraw sizes: W H [W H ...]")
    p.add_argument("--redraw-only", action="store_true", help="time only the redraws of the final stage")
    args = p.parse_args(argv)
    sizes = list(zip(args.res[0::2], args.res[1::2]))
    import bounce_gi

    bounce_gi.register()  # the scene settings, as the enabled extension has them
    try:
        for name in args.scenes:
            print_scene(name, args.method, bench_scene(name, args.method, sizes, args.redraw_only))
    finally:
        # Blender frees its GPU backend at exit before Python's last garbage collection: a shader or texture
        # still alive then (the compiled viewport shader is a module global) crashed the exit with SIGSEGV.
        # Disabling the extension releases them, and the engine's GL thread, first.
        bounce_gi.unregister()


if __name__ == "__main__":
    main()
