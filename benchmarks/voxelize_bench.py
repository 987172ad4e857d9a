# SPDX-License-Identifier: GPL-3.0-or-later
"""Voxelisation time and coverage, laid out like Freed 2018, Table 5.2 (rasterised vs tessellated, 64³–256³).

For each mesh and grid: median of --repeats timed runs after one warm-up (ctx.finish() inside the timing: the
whole pass — clear, draw, resolve into four RGBA32F volumes), the surface-voxel IoU against trimesh's
`voxelized(pitch)` on the same lattice, and the relative error of the total area. A "no triangles" row gives
the fixed cost (clearing and resolving the volumes), which dominates at 256³ on a software renderer.
Prints numbers; asserts nothing.

    .venv/bin/python benchmarks/voxelize_bench.py [--res 64 128 256] [--repeats 5] [--supersample 2] [mesh ...]
"""
import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# Freed 2018, Table 5.2 (GTX 970, the thesis' Sponza-like scene; rasterised with MSAA conservative rasterisation).
SEED_TABLE = {64: (0.53, 0.70), 128: (0.85, 1.12), 256: (1.91, 2.35)}


def meshes(names):
    import trimesh

    rng = np.random.default_rng(0)

    def terrain(n=201, size=10.0):
        x, y = np.meshgrid(np.linspace(0, size, n), np.linspace(0, size, n))
        z = 0.6 * np.sin(x * 0.9) * np.cos(y * 0.7) + 0.25 * np.sin(2.3 * x + 1.1 * y) + rng.normal(0, 0.02, x.shape)
        v = np.stack([x, y, z], axis=-1).reshape(-1, 3)
        i = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
        f = np.concatenate([np.stack([i, i + 1, i + n + 1], 1), np.stack([i, i + n + 1, i + n], 1)])
        return trimesh.Trimesh(v, f, process=False)

    def room():
        # A Cornell-like room: five 2 m walls and two boxes; few, large triangles (exercises the CPU split).
        walls = trimesh.creation.box(extents=(2, 2, 2))
        walls.faces = walls.faces[~np.isclose(walls.face_normals[:, 1], -1)]  # open the front (−y) side
        tall = trimesh.creation.box(extents=(0.6, 0.6, 1.2),
                                    transform=trimesh.transformations.compose_matrix(angles=(0, 0, 0.3),
                                                                                     translate=(-0.4, 0.3, -0.4)))
        short = trimesh.creation.box(extents=(0.6, 0.6, 0.6),
                                     transform=trimesh.transformations.compose_matrix(angles=(0, 0, -0.3),
                                                                                      translate=(0.4, -0.3, -0.7)))
        return trimesh.util.concatenate([walls, tall, short])

    table = {
        "sphere_5k": lambda: trimesh.creation.icosphere(subdivisions=4),
        "room_32": room,
        "terrain_80k": terrain,
        "sphere_82k": lambda: trimesh.creation.icosphere(subdivisions=6),
    }
    return {name: table[name]() for name in (names or table)}


def trimesh_occupancy(mesh, grid):
    """trimesh's surface voxels on our lattice (see tests/gpu/test_voxelize.py: voxel k is centred on k·pitch)."""
    shifted = mesh.copy()
    shifted.apply_translation(-(np.asarray(grid.origin) + 0.5 * grid.cell))
    idx = np.round(shifted.voxelized(grid.cell).points / grid.cell).astype(int)
    inside = np.all((idx >= 0) & (idx < grid.size), axis=1)
    occ = np.zeros(grid.shape_zyx, bool)
    occ[idx[inside, 2], idx[inside, 1], idx[inside, 0]] = True
    return occ


def parse_args():
    parser = argparse.ArgumentParser()
    parser.add_argument("meshes", nargs="*")
    parser.add_argument("--res", nargs="+", type=int, default=[64, 128, 256])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--supersample", type=int, default=2)
    parser.add_argument("--no-iou", action="store_true", help="skip trimesh (slow for big flat faces at 256³)")
    return parser.parse_args()


def to_scene(mesh):
    from bounce_gi.gpu_kernels.scene import Material, Scene

    pos = np.asarray(mesh.triangles, np.float32)
    t = len(pos)
    return Scene(pos, np.repeat(np.asarray(mesh.face_normals, np.float32)[:, None], 3, axis=1),
                 np.zeros((t, 3, 2), np.float32), np.zeros(t, np.int32), [Material("m")])


def timed(gl, scene, geometry, grid, mode, args):
    """(median seconds of --repeats voxelisations after a warm-up, the area channel of the last one)."""
    from bounce_gi.gpu_kernels.voxel import voxelize as vz

    ctx, programs = gl
    vz.voxelize(ctx, programs, scene, geometry, [], grid, mode=mode, supersample=args.supersample).release()
    times, volumes = [], None
    for _ in range(args.repeats):
        if volumes is not None:
            volumes.release()
        ctx.finish()
        start = time.perf_counter()
        volumes = vz.voxelize(ctx, programs, scene, geometry, [], grid, mode=mode, supersample=args.supersample)
        ctx.finish()
        times.append(time.perf_counter() - start)
    area = np.frombuffer(volumes.area.read(), np.float32).reshape(*grid.shape_zyx, 4)[..., 3]
    volumes.release()
    return statistics.median(times), area


def fixed_cost_rows(gl, args) -> list:
    """One "no triangles" row per grid: clearing and resolving the volumes alone."""
    from bounce_gi.gpu_kernels.common.grid import Grid
    from bounce_gi.gpu_kernels.direct import geometry as direct
    from bounce_gi.gpu_kernels.scene import Material, Scene
    from bounce_gi.gpu_kernels.voxel import voxelize as vz

    rows = []
    empty = Scene(np.zeros((0, 3, 3), np.float32), np.zeros((0, 3, 3), np.float32), np.zeros((0, 3, 2), np.float32),
                  np.zeros(0, np.int32), [Material("m")])
    geometry = direct.upload_geometry(*gl, empty)
    for res in args.res:
        grid = Grid((0.0, 0.0, 0.0), 1.0, (res, res, res))
        rows.append(("no triangles (fixed cost)", 0, grid.size, *(timed(gl, empty, geometry, grid, m, args)[0]
                                                                 for m in vz.MODES),
                     None, None, None, None))
    geometry.release()
    return rows


def mesh_rows(gl, name, mesh, args) -> list:
    """Time, IoU against trimesh and area error of both voxelizers, per grid, for one mesh."""
    from bounce_gi.gpu_kernels.common.grid import Grid
    from bounce_gi.gpu_kernels.direct import geometry as direct
    from bounce_gi.gpu_kernels.voxel import voxelize as vz

    rows = []
    scene = to_scene(mesh)
    geometry = direct.upload_geometry(*gl, scene)
    for res in args.res:
        grid = Grid.fit(*scene.bounds(), res)
        ref = None if args.no_iou else trimesh_occupancy(mesh, grid)
        row = [name, scene.triangle_count, grid.size]
        stats = []
        for mode in vz.MODES:
            seconds, area = timed(gl, scene, geometry, grid, mode, args)
            row.append(seconds)
            occ = area > 0
            iou = None if ref is None else np.count_nonzero(occ & ref) / np.count_nonzero(occ | ref)
            stats += [iou, area.sum(dtype=np.float64) / mesh.area - 1.0]  # (iou, err) per mode
        rows.append((*row, *stats))
        print(f"  done {name} {res}³", file=sys.stderr)
    geometry.release()
    return rows


def print_table(rows) -> None:
    fmt = lambda v, f: "—" if v is None else format(v, f)  # noqa: E731
    print(f"\n{'mesh':26s} {'tris':>6s} {'grid':>11s} | {'raster ms':>9s} {'tess ms':>8s} | "
          f"{'IoU r':>6s} {'IoU t':>6s} | {'area err r':>10s} {'area err t':>10s}")
    for name, tris, size, t_r, t_t, iou_r, err_r, iou_t, err_t in rows:
        grid = "×".join(map(str, size))
        print(f"{name:26s} {tris:6d} {grid:>11s} | {t_r * 1000:9.1f} {t_t * 1000:8.1f} | "
              f"{fmt(iou_r, '6.3f')} {fmt(iou_t, '6.3f')} | {fmt(err_r, '10.1e')} {fmt(err_t, '10.1e')}")
    print("\nFreed 2018, Table 5.2 (GTX 970, ms): " +
          "; ".join(f"{r}³ raster {a:.2f} tess {b:.2f}" for r, (a, b) in SEED_TABLE.items()))


def main():
    args = parse_args()

    from bounce_gi.gpu_kernels.gl.context import create_context
    from bounce_gi.gpu_kernels.gl.programs import ProgramCache

    ctx = create_context()
    programs = ProgramCache(ctx)
    gl = (ctx, programs)
    print(f"GL: {ctx.info['GL_RENDERER']} ({ctx.version_code}); supersample {args.supersample}; "
          f"median of {args.repeats} after a warm-up")
    rows = fixed_cost_rows(gl, args)
    for name, mesh in meshes(args.meshes).items():
        rows += mesh_rows(gl, name, mesh, args)
    print_table(rows)
    programs.release()
    ctx.release()

if __name__ == "__main__":
    main()
