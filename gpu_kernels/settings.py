# SPDX-License-Identifier: GPL-3.0-or-later
"""What a render is asked for: the method, the resolution and each stage's settings; and the checks that turn bad
input into one clear message (SceneError) before any GPU work starts."""
from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from .common.lights import ShadowSettings
from .lpv.settings import LpvSettings
from .scene import Scene, finite_normals
from .vct.settings import VctSettings

METHODS = ("none", "lpv", "vct")
# GPU memory a method's volumes take: bytes per voxel plus a fixed part, every texture and buffer a render allocates
# included (tallied over renders at 16³–48³: VCT 928 B of 3D textures — 912 before its faces' albedo, 48 B, came and
# the voxelizer's albedo and emission, 32 B, went — + ≤ 25 B of buffers per voxel of its padded
# grid; LPV ≤ 1976 B of 3D textures (its geometry volume at twice the resolution included) + 170–320 B of buffers per
# cell of each cascade, and ≈ 4 MB of VPL buffers at any size; the LPV's three voxelisations per axis
# (lpv/receivers.py) are held one at a time). tests/stress/test_grids_bounces.py holds these to the peak of what a
# render holds at once, so a volume added but not counted here fails a test. VCT's injection adds its cover
# test's front-most images (vct/inject.front_bytes, sized by the grid's largest side), the lights' parts it sums
# (vct/parts.parts_bytes) and its recorded cone samples (vct/replay.pool_bytes, sized by the surface area and the
# traced image).
VCT_BYTES_PER_VOXEL, VCT_FIXED_BYTES = 956, 2 ** 20
LPV_BYTES_PER_CELL, LPV_FIXED_BYTES = 2300, 8 * 2 ** 20
# A triangle is degenerate when twice its area is below this fraction of its longest edge squared: its height is
# under 2⁻²³ of that edge, float32's rounding of its corners.
DEGENERATE = 2.0 ** -23
TRIANGLE_ARRAYS = ("positions", "normals", "uvs", "material_index")


class SceneError(ValueError):
    """The scene cannot be rendered as given (message is for the user)."""


@dataclass(frozen=True)
class RenderSettings:
    method: str = "none"
    width: int = 640
    height: int = 480
    shadow: ShadowSettings = field(default_factory=ShadowSettings)
    lpv: LpvSettings = field(default_factory=LpvSettings)
    vct: VctSettings = field(default_factory=VctSettings)

    def key(self) -> str:
        return repr(sorted(asdict(self).items()))


def check_method(settings: RenderSettings) -> None:
    if settings.method not in METHODS:
        raise SceneError(f"unknown method '{settings.method}' (choose from {', '.join(METHODS)})")


def check_renderable(scene: Scene, settings: RenderSettings) -> None:
    """A render from the scene camera: a known method, a camera, a sane resolution."""
    check_method(settings)
    if scene.camera is None:
        raise SceneError("the scene has no camera")
    if settings.width < 1 or settings.height < 1 or settings.width > 16384 or settings.height > 16384:
        raise SceneError(f"resolution {settings.width}x{settings.height} is out of range (1..16384)")
    if not np.isfinite(scene.camera.matrix_world).all():
        raise SceneError("the scene camera's transform is NaN or infinite")
    check_materials(scene)
    check_memory(scene, settings)


def method_bytes(scene: Scene, settings: RenderSettings) -> int:
    """About how many bytes of GPU memory the method's volumes take (0 for "none")."""
    if settings.method == "vct":
        from .vct.inject import front_bytes
        from .vct.parts import parts_bytes, scene_parts
        from .vct.replay import pool_bytes
        from .vct.settings import traced_texels
        from .vct.volumes import vct_grid
        from .voxel.voxelize import scene_area

        grid = vct_grid(scene, settings.vct)
        traced = traced_texels(settings.width, settings.height, settings.vct)
        return (grid.voxel_count * VCT_BYTES_PER_VOXEL + front_bytes(grid) + VCT_FIXED_BYTES
                + pool_bytes(scene_area(scene), grid.cell, traced) + parts_bytes(grid, scene_parts(scene)))
    if settings.method == "lpv":
        from .lpv.state import cascade_grids

        from .lpv.passes import transfer_bytes

        cells = sum(g.voxel_count for g in cascade_grids(scene, settings.lpv))
        return cells * LPV_BYTES_PER_CELL + LPV_FIXED_BYTES + transfer_bytes(scene, settings.lpv)[0]
    return 0


def available_memory() -> int | None:
    """Bytes of memory the system can still give (Linux: MemAvailable), None where unknown. A software renderer
    (Mesa llvmpipe) keeps its textures there, and a driver past it kills the process rather than raising."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_memory(scene: Scene, settings: RenderSettings) -> None:
    """A grid too large for the memory there is: one clear message before any allocation. (On a discrete GPU
    with less memory than the host, the allocation fails instead: the engine reports that as GpuFailedError.)"""
    need, have = method_bytes(scene, settings), available_memory()
    if settings.method == "lpv":  # the LPV's cached transfer lives in host memory
        from .lpv.passes import transfer_bytes

        need += transfer_bytes(scene, settings.lpv)[1]
    if have is not None and need > have:
        res = settings.vct.resolution if settings.method == "vct" else settings.lpv.resolution
        raise SceneError(f"the {settings.method.upper()} grid (resolution {res}) needs about {need / 2 ** 30:.1f} GiB "
                         f"of memory, more than the {have / 2 ** 30:.1f} GiB available; lower its resolution")


def check_materials(scene: Scene) -> None:
    """Every triangle's material index names a material."""
    index = np.asarray(scene.material_index)
    if index.size and (index.min() < 0 or index.max() >= len(scene.materials)):
        raise SceneError(f"material index {int(index.max() if index.max() >= len(scene.materials) else index.min())}"
                         f" is out of range ({len(scene.materials)} materials)")


def repair_scene(scene: Scene) -> Scene:
    """The scene with what cannot be rendered left out, each with a warning, so one broken part never costs the user
    the whole render: triangles with a NaN or infinite vertex, lights with a non-finite power or position;
    degenerate triangles (no area, within float32 rounding) are left out silently; non-finite or zero shading
    normals become the geometric normal. The scene itself when nothing needs it.
    Extraction already leaves broken objects out by name (addon/extract/meshes.py); this covers scenes built any
    other way. A material index out of range is a SceneError (check_renderable)."""
    arrays = {name: np.asarray(getattr(scene, name)) for name in TRIANGLE_ARRAYS}
    finite = np.isfinite(arrays["positions"]).all(axis=(1, 2))
    warnings = [] if finite.all() else [f"{int((~finite).sum())} triangle(s) with a NaN or infinite vertex position "
                                        "left out"]
    keep = finite & ~_degenerate(arrays["positions"])
    changed = not keep.all()
    if changed:
        arrays = {name: a[keep] for name, a in arrays.items()}
    normals = finite_normals(arrays["positions"], arrays["normals"])
    if normals is not arrays["normals"]:
        arrays["normals"], changed = normals.astype(np.float32), True
    lights = [light for light in scene.lights if _finite_light(light)]
    warnings += [f"light '{light.name}' has a NaN or infinite power, colour or transform and is left out"
                 for light in scene.lights if not _finite_light(light)]
    if not changed and len(lights) == len(scene.lights):
        return scene
    return replace(scene, **arrays, lights=lights, warnings=list(scene.warnings) + warnings)


def _degenerate(positions: np.ndarray) -> np.ndarray:
    """Triangles that are lines, not surfaces, within float32 rounding (collinear corners, a corner twice, one
    point): left out silently, as meshes often have some. They cover no pixel, but a sliver still made its voxel a
    surface voxel with a full normal."""
    p = positions.astype(np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        edge2 = np.max([((p[:, i] - p[:, (i + 1) % 3]) ** 2).sum(axis=1) for i in range(3)], axis=0) \
            if len(p) else np.zeros(0)
        return ~(area2 > DEGENERATE * edge2)


def _finite_light(light) -> bool:
    values = [light.power, light.radius, light.size, light.size_y, *light.color]
    return all(math.isfinite(float(v)) for v in values) and bool(np.isfinite(light.matrix_world).all())
