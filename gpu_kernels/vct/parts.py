# SPDX-License-Identifier: GPL-3.0-or-later
"""vct_inject by parts: the lamps, the emissive meshes and the sky injected apart, each per unit of its own largest
colour, and summed (vct/inject_sum.glsl).

Why: the injection is linear in the lights (each surface point's light is a sum over them, vct/inject_raster.glsl),
so the faces of all lights are the sum of the faces of each part, each part's scaled by its colour. A light edit then
re-injects the part it touched and keeps the others' faces: a lamp's move re-lights the voxels from the lamps alone,
not from the sky's 144 shadow maps or an emissive mesh's clusters (seconds in a furnished room on llvmpipe). Where
a part is one light whose colour or power alone changed (the sky's colour or strength, a scene's only lamp), its
records per unit of its colour are unchanged and nothing is injected: the parts are summed with the new weights.
The bounces that follow run as after any light edit (vct/replay.py replays them).

The parts hold the light arriving at each face per unit albedo (vct/inject.py); their sum is multiplied by the
faces' albedo (vct/inject.face_albedo), so a material's colour edit re-makes the albedo and the sum, not the parts.
A cold render injects and sums the same parts, so it gives what an edit gives; a scene with one part sums it alone
(a copy: six more face volumes). Each part keeps six face volumes (PART_BYTES_CAP bounds the parts of a scene with
more than one): more than fit fall back to one part of every light (ALL). A part's key holds its lights' shadow
views as packed in the atlas, so a light added or removed elsewhere, which moves the maps in the atlas, injects
every part again.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common import lights as lb
from ..direct.shadows import emitter_records
from ..gl.bind import bind_named, dispatch, set_uniform, texture3d
from ..scene import Scene, hash_parts
from .colours import largest_colour
from .inject import face_flux
from .volumes import FaceAlbedo, Faces

PARTS = ("lamps", "emitters", "sky")  # the pass of each is vct_inject_<name>
ALL = "all"  # vct_inject_all: every light in one part, where the parts' face volumes would not fit
PART_BYTES_CAP = 128 * 2 ** 20  # the parts' face volumes together (a part at 64³: 24 MiB)
FACE_BYTES = 6 * 16  # six RGBA32F face volumes a voxel


@dataclass
class Part:
    """A group of light records injected together: `lights` their indices, `scale` (3,) their largest colour per
    channel (1 where none has any), by which the records it injects are divided (colours.unit_records)."""
    name: str
    lights: np.ndarray
    scale: np.ndarray


def light_parts(shadows) -> list[Part]:
    """The non-empty parts of the shadows' light records, in PARTS order: the sky light(s), the emissive meshes'
    clusters (triangle lists), and every other light (the lamps)."""
    records = shadows.buffers.lights
    emitter = emitter_records(records)
    sky = records["color_type"][:, 3].astype(int) == lb.LIGHT_SKY
    masks = {"lamps": ~emitter & ~sky, "emitters": emitter, "sky": sky}
    out = []
    for name in PARTS:
        lights = np.flatnonzero(masks[name])
        if len(lights):
            out.append(Part(name, lights, largest_colour(records["color_type"][lights, :3])))
    return out


def injected_parts(shadows, grid) -> list[Part]:
    """The parts the lights are injected in: light_parts, or, where their face volumes would not fit `grid` (or
    there is no light), one part ALL of every light."""
    found = light_parts(shadows)
    if found and fits(grid, len(found)):
        return found
    records = shadows.buffers.lights
    return [Part(ALL, np.arange(len(records)), largest_colour(records["color_type"][:, :3]))]


def scene_parts(scene: Scene) -> int:
    """How many parts `scene`'s lights make (settings.method_bytes: before any light record exists)."""
    lamps = any(light.power > 0 for light in scene.lights)
    emitters = scene.has_emission()
    sky = max(np.asarray(scene.world.color, np.float64)[:3], default=0.0) > 0
    return int(lamps) + int(emitters) + int(sky)


def fits(grid, parts: int) -> bool:
    """Whether `parts` parts are injected apart on `grid`: one always (it is every light), more where their face
    volumes fit PART_BYTES_CAP."""
    return parts <= 1 or parts * grid.voxel_count * FACE_BYTES <= PART_BYTES_CAP


def parts_bytes(grid, parts: int) -> int:
    """The memory the parts add on `grid` to the faces they sum to: their face volumes (six a part), or where they
    do not fit, those of the one injection of every light the sum is made from."""
    return (parts if fits(grid, parts) else min(parts, 1)) * grid.voxel_count * FACE_BYTES


def part_key(shadows, part: Part, records: np.ndarray) -> str:
    """What a part's injection is made of besides the voxels: its lights' maps and records without their colours
    (direct/shadows.light_signatures) and their colours per unit of its scale."""
    return hash_parts([shadows.light_keys[i] for i in part.lights], records["color_type"][:, :3])


def sum_parts(ctx, programs, parts: list, weights: list, albedo: FaceAlbedo, centroids: list) -> Faces:
    """New faces albedo ⊙ Σ_p weights[p] ⊙ parts[p] (rgb: each part's light per unit albedo; the coverage α, the
    geometry's, from any part), with the kept `centroids` (not owned), and their statistics (inject.face_flux)."""
    first = parts[0]
    out = Faces([texture3d(ctx, first.grid.size, zero=True) for _ in range(6)], first.grid, first.levels,
                centroids=centroids, centroids_owned=False)
    prog = programs.compute("vct/inject_sum.glsl")
    set_uniform(prog, "u_grid_size", tuple(int(n) for n in first.grid.size))
    set_uniform(prog, "u_parts", len(parts))
    for p, w in enumerate(list(weights) + [np.zeros(3)] * (len(PARTS) - len(parts))):
        set_uniform(prog, f"u_weight{p}", tuple(float(c) for c in w))
    for i, texture in enumerate(out.textures):
        faces = [f.textures[i] for f in parts]
        bind_named(prog, [(f"u_part{p}", faces[min(p, len(faces) - 1)]) for p in range(len(PARTS))]
                   + [("u_albedo", albedo.textures[i])])
        texture.bind_to_image(0, read=False, write=True)
        dispatch(prog, first.grid.size)
    ctx.memory_barrier()
    out.flux, out.occupied, out.missed = face_flux(ctx, programs, out)
    return out
