# SPDX-License-Identifier: GPL-3.0-or-later
"""The viewport's fitted diffuse share (ui/draw.py POLY variant, common/principled.share_polynomial) draws the same
image as the table lookup it replaces, on the example scene whose every surface has Blender's default Principled
BSDF (a view-dependent share on all of it) — the drawing path `bounce-gi snapshot` and Rendered shading share."""
import os
import subprocess
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

CASE = """
import numpy as np
import bpy
from examples import scenes
from bounce_gi.addon.extract import extract_scene
from bounce_gi.gpu_kernels.engine import get_engine
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.ui import draw

scenes.build("default_principled")
scene = extract_scene(bpy.context.evaluated_depsgraph_get(), (160, 120))
light = get_engine().submit_surface(scene, RenderSettings(method="none", width=160, height=120), 65536).result()
draw.ensure_gpu()
images = {}
for name, tolerance in (("poly", draw.POLY_TOLERANCE), ("table", -1.0)):
    draw.POLY_TOLERANCE = tolerance
    drawing = draw.SurfaceDrawing(light)
    variants = sorted({share for (share, _flat), *_ in drawing.parts})
    drawing.free()
    images[name] = draw.snapshot(light, scene, 160, 120)[..., :3]
    print(name, variants)
diff = np.abs(images["poly"] - images["table"])
print(f"RESULT max {diff.max():.2e} rel-L1 {diff.sum() / np.abs(images['table']).sum():.2e}")
"""


def _run(case: str, tmp_path):
    """`case` in a fresh background-bpy process with the repository importable as bounce_gi; it must exit 0."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), ROOT])}
    os.symlink(ROOT, tmp_path / "bounce_gi")
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(case)], capture_output=True, text=True,
                          timeout=600, cwd=ROOT, env=env)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc


def test_the_fitted_share_draws_what_the_table_draws(tmp_path):
    proc = _run(CASE, tmp_path)
    lines = proc.stdout.splitlines()
    drawn = {line.split()[0]: line for line in lines if line.split()[:1] in (["poly"], ["table"])}
    # Every Principled part fits, with one polynomial for its three channels (no coat tint) ...
    assert "'grey'" in drawn["poly"] and "'table'" not in drawn["poly"], drawn
    assert "'table'" in drawn["table"] and "'grey'" not in drawn["table"], drawn  # ... and none with fits off
    result = next(line for line in lines if line.startswith("RESULT")).split()
    # Every material's polynomial is within POLY_TOLERANCE (1e-3) of its table row, and the light it multiplies
    # is below 1 here; the table's own linear interpolation between its texels differs from the exact share by
    # less than that again. So no pixel may differ by more than 2e-3. Over the image: the default Principled's fit
    # is within 1.7e-4 of its row, a share near 0.9, so rel-L1 at most 2e-4 (measured: max 1.5e-4, rel-L1 4.7e-5).
    assert float(result[2]) <= 2e-3 and float(result[4]) <= 2e-4, result


WARM = """
import time
import bpy
from examples import scenes
from bounce_gi.addon.extract import extract_scene
from bounce_gi.gpu_kernels.engine import get_engine
from bounce_gi.gpu_kernels.settings import RenderSettings
from bounce_gi.ui import draw

scenes.build("furnished")
scene = extract_scene(bpy.context.evaluated_depsgraph_get(), (160, 120))
light = get_engine().submit_surface(scene, RenderSettings(method="none", width=160, height=120), 16384).result()
draw.ensure_gpu()
drawing = draw.SurfaceDrawing(light)
first = draw.shaders_to_compile(drawing)
ticks, times = 0, []
while True:
    start = time.perf_counter()
    more = draw.compile_next_shader(drawing)
    times.append(time.perf_counter() - start)
    ticks += 1
    if not more or ticks > 100:
        break
warmed = not draw.cold_variants(drawing)  # every variant of every mode drawn once
print("RESULT", len(first), ticks, len(draw.shaders_to_compile(drawing)), max(times), warmed)
"""


def test_the_display_modes_shaders_are_compiled_and_drawn_once_ahead_of_a_switch(tmp_path):
    """A new drawing compiles its variants of the default (Combined) display and draws each once into a 1×1 buffer
    like the 3D view's; after a result is shown, the viewport's timer does the same for the other display modes, one
    variant a tick (ui/draw.compile_next_shader: compile, then draw), so a later switch of mode draws at once (the
    driver builds a variant's code for the framebuffer at its first draw: benchmarks/results/viewport_llvmpipe.md
    measures the switch). On the furnished room (its parts: several variants) every variant of the other two modes
    gets compiled and drawn, one per call, the last call says nothing is left, and every variant of all three modes
    has been drawn."""
    proc = _run(WARM, tmp_path)
    result = next(line for line in proc.stdout.splitlines() if line.startswith("RESULT")).split()
    print("variants to compile, calls, left, longest call (s):", result[1:])
    first, ticks, left = (int(v) for v in result[1:4])
    assert first >= 4 and first % 2 == 0  # two variants or more, each in the two other display modes
    assert ticks == 2 * first and left == 0 and result[5] == "True"  # each compiled, then each drawn
