# SPDX-License-Identifier: GPL-3.0-or-later
"""The cached transport's receivers (lpv/transfer.py): a surface voxel's surfaces split by the dominant axis of their
normals — one receiver per voxel and axis, with its own mean normal, area and albedo per side — each where its
surfaces lie (their area-weighted centroid), not at the voxel's centre, with the box they span.

Why: where a floor meets a wall, one voxel holds both. As one receiver at the voxel's centre it had their mean
normal, 45° from either surface, the irradiance of that diagonal plane, and the clusters of both walls passing
through it, seen edge-on: in a closed furnace box (uniform radiosity) such edge voxels received 0.49–0.50 of the exact
irradiance and corner voxels 0.23–0.24, so every bounce lost a share of the light (3.4% of the box's area at 32³, 18%
at 8³: 0.70 of the series after 8 bounces at albedo 1). Split by axis and placed on their surfaces, the floor's part
is a floor beside the wall and sees it through the transfer's near field (lpv/gather.glsl polygon_kernel, over
the octagon the wall's surfaces span): edge receivers now get 0.97–0.99 of it, the whole box 0.99–0.995 per bounce.
Godot's VoxelGI and Crassin's anisotropic voxels keep light per axis direction for the same reason: one value per
voxel cannot tell two surfaces that meet in it apart.

The receivers come from three voxelisations of one fine grid, each of the triangles of one dominant axis
(voxel/voxelize.py axis_only, positions); the geometry volume's blocking and visibility planes
(lpv/crossings.py) use their sum. The flux lookup (lpv/lighting.glsl) reads their irradiance from six volumes of the
fine grid (axis × side) written after each solve, filtered: three fetches per pixel; a grid too large for them
(LIGHT_VOLUME_BYTES) through a sparse index per fine voxel into the light records instead.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.grid import Grid
from ..gl.bind import ssbo
from ..scene import Scene, hash_parts
from . import regional
from .crossings import Surfaces, crossing_layers, volume_fields
from .occlusion import KEEP_FRONT_BYTES, GeometryVolume, face_blocking, fine_grid, layer_area, side_albedo
from .wall_sides import clip_to_walls

AXES = 3


def _per_axis(ctx, programs, scene: Scene, geometry, textures, fine: Grid, names, front=None, albedo_override=None,
              region=None):
    """[arrays of axis 0, 1, 2] (VoxelVolumes.read(names)) and the front-most image every pass shared (made by the
    first pass unless `front` is given; None where the grid keeps one albedo per voxel); of the voxels `region`
    (lo, hi) only, where given (voxelize)."""
    from ..voxel.voxelize import voxelize

    out = []
    for axis in range(AXES):
        vox = voxelize(ctx, programs, scene, geometry, textures, fine, sides=True, front=front,
                       keep_front=front is None, axis_only=axis, positions="position" in names,
                       albedo_override=albedo_override, region=region)
        front = front if front is not None else vox.front
        out.append(vox.read(names))
        vox.release()
    return out, front


def receiver_order(cells: np.ndarray, axis: np.ndarray, fine: Grid) -> np.ndarray:
    """The permutation that sorts receivers by fine voxel, then axis (the order receiver_index and the light
    records use)."""
    nx, ny, _ = (int(n) for n in fine.size)
    lin = (cells[:, 2].astype(np.int64) * ny + cells[:, 1]) * nx + cells[:, 0]
    return np.lexsort((axis, lin))


def receiver_index(cells: np.ndarray, axis: np.ndarray, fine: Grid) -> np.ndarray:
    """(nz, ny, nx) int32 per fine voxel: 8 × its first receiver + a mask of the axes it has receivers for (bit a),
    0 for a voxel without; receivers in receiver_order."""
    nx, ny, nz = (int(n) for n in fine.size)
    out = np.zeros((nz, ny, nx), np.int64)
    np.bitwise_or.at(out, (cells[:, 2], cells[:, 1], cells[:, 0]), 1 << axis.astype(np.int64))
    lin = (cells[:, 2].astype(np.int64) * ny + cells[:, 1]) * nx + cells[:, 0]
    first = np.full(nx * ny * nz, np.iinfo(np.int64).max)
    np.minimum.at(first, lin, np.arange(len(lin)))
    has = first < len(lin)
    flat = out.reshape(-1)
    flat[has] += 8 * first[has]
    if len(lin) and 8 * len(lin) >= 2 ** 31:
        raise ValueError(f"{len(lin)} receivers do not fit the flux lookup's 28-bit index")
    return out.astype(np.int32)


def _index_texture(ctx, cells: np.ndarray, axis: np.ndarray, fine: Grid):
    """receiver_index as an r32i fine-grid texture, read nearest."""
    import moderngl

    t = ctx.texture3d(tuple(fine.size), 1, receiver_index(cells, axis, fine).tobytes(), dtype="i4")
    t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return t


def axis_volumes(ctx, programs, scene: Scene, geometry, textures, grids: list, prior: list | None = None,
                 materials=None) -> list:
    """Geometry volumes (occlusion.GeometryVolume) whose surface voxels are receivers per dominant axis: the
    blocking and visibility planes from all surfaces, the receivers' normals, areas and albedo per axis.
    `prior`: geometry volumes of the same grids made before an edit, whose kept voxelisation an object's move
    updates (lpv/regional.py); `materials`: the pipeline's key of the materials' colours and textures."""
    import moderngl

    out = []
    inputs = regional.inputs_key(scene, materials)
    for k, grid in enumerate(grids):
        fine = fine_grid(grid)
        kept = prior[k].voxels if prior and k < len(prior) else None
        arrays, front, share = _voxelised(ctx, programs, scene, geometry, textures, fine, kept, inputs)
        area, normal, surfaces = _combined(arrays)
        r = _receivers(arrays, fine)
        blocking = ctx.texture3d(tuple(n + 1 for n in grid.size), 4, face_blocking(area, grid).tobytes(), dtype="f4")
        blocking.filter = (moderngl.NEAREST, moderngl.NEAREST)
        records = np.zeros((len(r["cells"]), 4), np.int32)
        records[:, :3] = r["cells"]
        oriented = np.zeros((len(r["cells"]), 2, 4), np.float32)  # lpv/gather.glsl MODE_TRANSFER's Receivers
        oriented[:, 0, :3], oriented[:, 0, 3], oriented[:, 1, :3] = r["normals"], r["areas"], r["positions"]
        dense = light_volume_bytes(fine) <= LIGHT_VOLUME_BYTES
        crossings = crossing_layers(area, normal, grid, surfaces)
        out.append(GeometryVolume(
            blocking, fine, None, None, None, surfaces=ssbo(ctx, records), surface_count=len(r["cells"]),
            cells=r["cells"], surface_normal=r["normals"], surface_area=r["areas"], surface_albedo=r["albedo"],
            front=front, axis=r["axis"], positions=r["positions"], bounds=(r["lo"], r["hi"]),
            receivers=ssbo(ctx, oriented),
            light_volumes=make_light_volumes(ctx, fine, r["cells"], r["axis"]) if dense else None,
            receiver_index=None if dense else _index_texture(ctx, r["cells"], r["axis"], fine),
            voxels=regional.keep(arrays, scene, inputs), voxelised=share, crossings=crossings,
            **volume_fields(ctx, crossings)))
    return out


VOXEL_NAMES = ("area", "normal", "albedo", "albedo_back", "position", "extent_lo", "extent_hi")


def _voxelised(ctx, programs, scene: Scene, geometry, textures, fine: Grid, kept, inputs) -> tuple:
    """The three per-axis voxelisations of `fine`, the front-most image to keep (None: none) and the share of the
    grid voxelised: the whole grid, or after an object's move the region it changed voxelised into a copy of `kept`
    (lpv/regional.py), whose front-most image is right in the region only and is not kept."""
    from ..voxel.voxelize import front_bytes

    region = regional.moved_region(kept, scene, fine, inputs)
    if region is not None:
        part, front = _per_axis(ctx, programs, scene, geometry, textures, fine, VOXEL_NAMES, region=region)
        if front is not None:
            front.release()
        return regional.paste(kept.arrays(), region, part), None, float(np.prod(region[1] - region[0])) / \
            fine.voxel_count
    arrays, front = _per_axis(ctx, programs, scene, geometry, textures, fine, VOXEL_NAMES)
    if front is not None and front_bytes(fine, 2) > KEEP_FRONT_BYTES:
        front.release()
        front = None
    return arrays, front, 1.0


def _combined(arrays: list) -> tuple:
    """The three axes' voxelisations as one: area, mean normal and where the surfaces lie (crossings.Surfaces).
    The means and boxes are taken at the voxels with a surface only (most of a grid is empty)."""
    area = sum(a["area"] for a in arrays)
    occupied = np.flatnonzero(area[..., 3] > 0)
    rows = [{k: a[k].reshape(-1, 4)[occupied] for k in ("area", "normal", "position", "extent_lo", "extent_hi")}
            for a in arrays]
    total = area.reshape(-1, 4)[occupied, 3:]
    normal = np.zeros_like(area)
    normal.reshape(-1, 4)[occupied] = sum(r["area"][:, 3:] * r["normal"] for r in rows) / total
    centroid = np.full(area.shape[:3] + (3,), 0.5, np.float32)
    centroid.reshape(-1, 3)[occupied] = sum(r["area"][:, 3:] * r["position"][:, :3] for r in rows) / total
    own = np.stack([np.where(a["area"][..., 3] > 0, a["position"][..., i], np.nan) for i, a in enumerate(arrays)],
                   axis=-1)
    lo, hi = (np.full(area.shape[:3] + (3,), fill, np.float32) for fill in (np.inf, -np.inf))
    lo.reshape(-1, 3)[occupied] = np.stack([np.where(r["area"][:, 3:] > 0, r["extent_lo"][:, :3], np.inf)
                                            for r in rows]).min(axis=0)
    hi.reshape(-1, 3)[occupied] = np.stack([np.where(r["area"][:, 3:] > 0, r["extent_hi"][:, :3], -np.inf)
                                            for r in rows]).max(axis=0)
    return area, normal, Surfaces(centroid, own, lo, hi)


def _receivers(arrays: list, fine: Grid) -> dict:
    """Every voxel's receiver per axis, in receiver_order: cells, axis, normals, areas (one layer's at most),
    positions and the box their surfaces span (m; of the part in front of a wall that cuts it in its voxel:
    wall_sides.clip_to_walls), the way they face (voxel/resolve.glsl: normal w), albedo (2, R, 3)."""
    parts = []
    for axis, a in enumerate(arrays):
        z, y, x = np.nonzero(a["area"][..., 3] > 0)
        cells = np.stack([x, y, z], axis=1)
        n = a["normal"][z, y, x, :3]
        world = [np.asarray(fine.origin) + (cells + a[k][z, y, x, :3]) * fine.cell
                 for k in ("position", "extent_lo", "extent_hi")]
        span = (a["extent_hi"][z, y, x, :3] - a["extent_lo"][z, y, x, :3]) * fine.cell
        parts.append((cells, np.full(len(x), axis), n, layer_area(a["area"][z, y, x, 3], n, fine.cell, span), *world,
                      a["normal"][z, y, x, 3]))
    keys = ("cells", "axis", "normals", "areas", "positions", "lo", "hi", "facing")
    out = {k: np.concatenate([p[i] for p in parts]) for i, k in enumerate(keys)}
    order = receiver_order(out["cells"], out["axis"], fine)
    out = clip_to_walls({k: v[order] for k, v in out.items()}, fine.cell)
    out["albedo"] = np.concatenate([side_albedo(a, a_cells) for a, (a_cells, *_) in zip(arrays, parts)],
                                   axis=1)[:, order]
    return out


def axis_albedo(ctx, programs, scene: Scene, geometry, textures, gv: GeometryVolume,
                albedo_override=None) -> np.ndarray:
    """(2, R, 3): the two sides' albedo of `gv`'s receivers under the scene's current materials (a material edit
    changes no geometry: three voxelisations whose occupancy is discarded, the front-most image reused), or under
    `albedo_override` (voxel/voxelize.py)."""
    arrays, front = _per_axis(ctx, programs, scene, geometry, textures, gv.fine, ("albedo", "albedo_back"), gv.front,
                              albedo_override)
    if gv.front is None and front is not None:
        front.release()
    out = np.zeros((2, gv.surface_count, 3), np.float32)
    for axis, a in enumerate(arrays):
        mine = gv.axis == axis
        out[:, mine] = side_albedo(a, gv.cells[mine])
    return out


# A material edit without a voxelisation. A receiver side's albedo is the area-weighted mean of the albedo of the
# surfaces it sees (voxel/resolve.glsl), so for materials of one constant albedo each (no base-colour texture) it is
# Σ_m w_m · albedo_m, w_m the share of the side's seen area that material m covers — geometry only. An edit then
# costs, per edited material, its weights once (one voxelisation per axis with a one-hot colour, three materials a
# pass) and a multiply-add each time after: dragging a colour re-voxelises nothing after its first step.

def albedo_signature(scene: Scene, textures) -> list:
    """Per material index, what sets its voxel albedo (voxel/common.glsl voxel_albedo): ("rgb", albedo) for a
    constant one, ("texture", its content key, scale, offset) for a textured one."""
    out = []
    for m, mat in enumerate(scene.materials):
        scale, offset = (np.asarray(v, np.float64) for v in textures.transport[m])
        if 0 <= mat.base_color_texture < len(scene.textures):
            out.append(("texture", hash_parts(scene.textures[mat.base_color_texture]), tuple(scale), tuple(offset)))
        else:
            base = np.maximum(np.asarray(mat.base_color[:3], np.float64), 0.0)
            out.append(("rgb", tuple(base * scale + offset)))
    return out


def edited_materials(before: list | None, now: list) -> list | None:
    """The material indices whose constant albedo changed from `before` to `now`, or None where the linear update
    cannot follow the edit (no record, materials added or removed, a textured material edited)."""
    if before is None or len(before) != len(now):
        return None
    changed = [m for m, (b, n) in enumerate(zip(before, now)) if b != n]
    return None if any(before[m][0] != "rgb" or now[m][0] != "rgb" for m in changed) else changed


def material_weights(ctx, programs, scene: Scene, geometry, textures, gv: GeometryVolume, materials) -> dict:
    """{m: (2, R) float32}: the share of each receiver side's seen area that material m covers, for each m in
    `materials`, three a voxelisation (one-hot in r, g, b)."""
    out, materials = {}, list(materials)
    for i in range(0, len(materials), 3):
        group = materials[i:i + 3]
        one_hot = {m: tuple(float(j == k) for j in range(3)) for k, m in enumerate(group)}
        shares = axis_albedo(ctx, programs, scene, geometry, textures, gv, one_hot)
        out.update({m: np.ascontiguousarray(shares[..., k]) for k, m in enumerate(group)})
    return out


def current_albedo(ctx, programs, scene: Scene, geometry, textures, gv: GeometryVolume, materials_key: str):
    """(2, R, 3): `gv`'s receivers' albedo under the scene's current materials (`materials_key`): gv's own where it
    was made with them; after an edit of constant-albedo materials, gv's plus each edited material's weights × its
    change of albedo; else a re-voxelisation, which becomes gv's albedo for the next edit."""
    if gv.materials_key == materials_key:
        return gv.surface_albedo
    now = albedo_signature(scene, textures)
    changed = edited_materials(gv.material_signature, now)
    if changed is None:
        gv.surface_albedo = axis_albedo(ctx, programs, scene, geometry, textures, gv)
        gv.material_signature, gv.materials_key = now, materials_key
        return gv.surface_albedo
    missing = [m for m in changed if m not in gv.material_weights]
    gv.material_weights.update(material_weights(ctx, programs, scene, geometry, textures, gv, missing))
    out = gv.surface_albedo.astype(np.float64)
    for m in changed:
        delta = np.subtract(now[m][1], gv.material_signature[m][1])
        out += gv.material_weights[m][..., None] * delta
    return np.maximum(out, 0.0).astype(np.float32)  # rounding must not make a reflectance negative


LIGHT_VOLUME_BYTES = 256 * 2 ** 20  # the six dense volumes' budget (a 64-cell grid's fit), else the sparse index


def light_volume_bytes(fine: Grid) -> int:
    """Bytes of LightVolumes for a fine grid: six RGBA32F volumes."""
    return 6 * 16 * int(np.prod(fine.size))


def lookup_bytes(fine: Grid) -> int:
    """GPU bytes the flux lookup reads of a fine grid: LightVolumes where they fit LIGHT_VOLUME_BYTES, else the
    receiver_index texture (one int32 a voxel)."""
    dense = light_volume_bytes(fine)
    return dense if dense <= LIGHT_VOLUME_BYTES else 4 * int(np.prod(fine.size))


@dataclass
class LightVolumes:
    """Six RGBA32F volumes of a geometry volume's fine grid, axis a's side s at 2a + s, that lpv/lighting.glsl
    (MODE_RECEIVER_VOLUMES) filters: rgb a receiver's irradiance, a = 1 where it receives, zero where there is no
    receiver. Made zero once per geometry; each solve writes only its receivers' voxels (lpv/receiver_light.glsl),
    which a dense upload per solve would cost the whole grid's bytes. `cells`: the receivers' voxels and axes, the
    storage buffer the scatter reads; `holder`: the ReceiverLight whose light they hold now."""
    volumes: list
    cells: object
    holder: object = None

    def release(self):
        for t in self.volumes + [self.cells]:
            t.release()


def make_light_volumes(ctx, fine: Grid, cells: np.ndarray, axis: np.ndarray) -> LightVolumes:
    import moderngl

    from ..gl.bind import texture3d

    volumes = [texture3d(ctx, fine.size, zero=True) for _ in range(6)]
    for t in volumes:
        t.filter = (moderngl.LINEAR, moderngl.LINEAR)
    records = np.zeros((len(cells), 4), np.int32)
    records[:, :3], records[:, 3] = cells, axis
    return LightVolumes(volumes, ssbo(ctx, records))


@dataclass
class ReceiverLight:
    """What the flux lookup (lpv/lighting.glsl MODE_RECEIVER_VOLUMES or MODE_RECEIVERS) reads: the cached transport's
    one cascade's grid and geometry volume, and its receivers' irradiance per side, a storage buffer of (R, 2) vec4
    (front, back; a = 1 where it receives) in receiver_order — written into the geometry volume's LightVolumes
    (write_volumes) or read through its sparse receiver_index."""
    grids: list
    gvs: list
    records: object
    ctx: object = None
    programs: object = None

    def write_volumes(self) -> None:
        """Make the geometry volume's LightVolumes hold this light (a no-op where they already do)."""
        from ..gl.bind import bind_images, dispatch, set_uniform

        light = self.gvs[0].light_volumes
        if light is None or light.holder is self:
            return
        prog = self.programs.compute("lpv/receiver_light.glsl")
        self.records.bind_to_storage_buffer(6)
        light.cells.bind_to_storage_buffer(7)
        bind_images(light.volumes, read=False, write=True)
        set_uniform(prog, "u_count", int(self.gvs[0].surface_count))
        dispatch(prog, (max(int(self.gvs[0].surface_count), 1),), local=64)
        self.ctx.memory_barrier()
        light.holder = self

    def release(self):
        light = self.gvs[0].light_volumes
        if light is not None and light.holder is self:
            light.holder = None
        self.records.release()


def upload_light(ctx, programs, grids: list, gvs: list, sides: list) -> ReceiverLight:
    """The receivers' irradiance, (2, R, 3) per cascade in `sides` (one: the cached transport has no cascades), as a
    ReceiverLight, written into the LightVolumes where the geometry volume has them; a receiver with no area or
    normal receives nothing (a = 0)."""
    if len(gvs) != 1:
        raise ValueError("the cached transport has one cascade")
    gv, side = gvs[0], sides[0]
    valid = (gv.surface_area > 0) & (np.linalg.norm(gv.surface_normal, axis=1) > 0)
    records = np.zeros((len(valid), 2, 4), np.float32)
    records[:, :, :3] = np.where(valid[None, :, None], side, 0.0).transpose(1, 0, 2)
    records[:, :, 3] = valid[:, None]
    light = ReceiverLight(list(grids), list(gvs), ssbo(ctx, records), ctx, programs)
    light.write_volumes()
    return light
