# SPDX-License-Identifier: GPL-3.0-or-later
"""One helper per way a pass hands data to a shader: uniforms, samplers, images, dispatch, the grid, the lights,
and the texture allocations and read-backs every stage shares. Stages call these rather than moderngl directly,
so a uniform or a binding is spelled one way everywhere."""
from __future__ import annotations

import numpy as np


def set_uniform(prog, name, value):
    """Set a uniform if the compiler kept it (unused uniforms are optimised away)."""
    if name in prog:
        prog[name].value = value


def set_uniforms(prog, values: dict) -> None:
    """set_uniform for every (name, value) of `values`."""
    for name, value in values.items():
        set_uniform(prog, name, value)


def write_uniform(prog, name, array: np.ndarray) -> None:
    """Write a uniform (array, matrix) as raw float32 bytes if the compiler kept it."""
    if name in prog:
        prog[name].write(np.ascontiguousarray(array, np.float32).tobytes())


def bind_samplers(prog, name: str, textures: list, first: int, pad_to: int = 0) -> int:
    """Bind `textures` to consecutive texture units from `first` and point sampler (array) `name` at them, the
    array's unused tail (up to `pad_to` entries) at the last one; returns the next free unit."""
    for i, t in enumerate(textures):
        t.use(location=first + i)
    if name in prog:
        units = list(range(first, first + len(textures)))
        units += units[-1:] * (pad_to - len(units))
        prog[name].value = units if prog[name].array_length > 1 else units[0]
    return first + len(textures)


def bind_named(prog, samplers: list, first: int = 0) -> int:
    """bind_samplers for (sampler name, texture) pairs on consecutive units; returns the next free unit."""
    for name, texture in samplers:
        first = bind_samplers(prog, name, [texture], first)
    return first


def bind_images(textures: list, first: int = 0, read: bool = False, write: bool = True, level: int = 0) -> int:
    """Bind `textures` to consecutive image units from `first`; returns the next free unit."""
    for i, t in enumerate(textures):
        t.bind_to_image(first + i, read=read, write=write, level=level)
    return first + len(textures)


# The work group of every pass over a volume (the shaders declare it: layout(local_size_x = 8, local_size_y = 8,
# local_size_z = 1)). Flat rather than 4 × 4 × 4: llvmpipe runs a group's x invocations as one SIMD vector, and a
# resolve over 66³ voxels that mostly return at once took 68 ms as 4 × 4 × 4 groups, 20 ms as 8 × 8 × 1; GPUs
# run either at the same speed (64 invocations, two warps or one wavefront).
VOLUME_GROUP = (8, 8, 1)


def groups(size, local) -> tuple:
    """Work groups that cover `size` invocations per axis with `local` invocations per group (one int for every
    axis, or one per axis)."""
    local = (local,) * len(size) if isinstance(local, int) else tuple(local)
    return tuple((int(n) + k - 1) // k for n, k in zip(size, local))


def dispatch(prog, size, local=VOLUME_GROUP) -> None:
    """Run a compute program over `size` (1 to 3 axes) with work groups of `local` invocations (one int for every
    axis given, or one per axis; by default VOLUME_GROUP, the volume passes' group)."""
    g = groups(size, local)
    prog.run(*(g + (1,) * (3 - len(g))))


def dispatch_counted(ctx, prog, size, local: int = 8, counts: int = 1):
    """dispatch() a program that counts what it did in atomic uints on storage buffer 3; returns the count (or the
    first `counts` of them, a tuple, where it keeps more than one)."""
    counter = ctx.buffer(np.zeros(4, np.uint32).tobytes())
    try:
        counter.bind_to_storage_buffer(3)
        dispatch(prog, size, local)
        ctx.memory_barrier()
        values = tuple(int(v) for v in np.frombuffer(counter.read(), np.uint32)[:counts])
        return values[0] if counts == 1 else values
    finally:
        counter.release()


def bind_grid(prog, grid, levels: int | None = None) -> None:
    """The grid uniforms every voxel shader names alike: u_grid_origin, u_grid_cell, u_grid_size (and u_max_lod
    when the volumes have mip `levels`)."""
    set_uniform(prog, "u_grid_origin", tuple(float(c) for c in grid.origin))
    set_uniform(prog, "u_grid_cell", float(grid.cell))
    set_uniform(prog, "u_grid_size", tuple(int(n) for n in grid.size))
    if levels is not None:
        set_uniform(prog, "u_max_lod", float(levels - 1))


# The shadow atlas read without comparison (direct/eval.glsl u_shadow_depth: the soft shadows' blocker search) is a
# sampler object on the atlas, bound on a unit nothing else uses: a sampler stays bound to its unit and would
# override the filtering of any other texture put there. Not the last unit (31 of the 32 a stage may read): moderngl
# binds every texture it makes, reads or writes there (its default_texture_unit), which took the atlas's place
# between binding the lights and a dispatch.
RAW_DEPTH_UNIT = 30


def bind_lights(prog, shadows, unit: int, sky_stride: int = 1) -> int:
    """The lights, shadow views, polygons and shadow atlas of direct/eval.glsl (storage buffers 0–2, the atlas on
    texture unit `unit`); returns the next free unit. sky_stride: the sky is shadowed from every sky_stride-th of
    its directions (the injection's: common/lights.SKY_INJECTION_STRIDE)."""

    shadows.depth.use(location=unit)
    set_uniform(prog, "u_shadow_atlas", unit)
    if "u_shadow_depth" in prog:
        shadows.raw_depth().use(location=RAW_DEPTH_UNIT)
        set_uniform(prog, "u_shadow_depth", RAW_DEPTH_UNIT)
    set_uniform(prog, "u_sky_stride", int(sky_stride))
    set_uniform(prog, "u_atlas_texel", (1.0 / shadows.size[0], 1.0 / shadows.size[1]))
    set_uniform(prog, "u_light_count", shadows.light_count)
    bind_light_records(shadows)
    return unit + 1


def bind_light_records(shadows) -> None:
    """The light, shadow-view and polygon records of common/lights.glsl on storage buffers 0, 1, 2."""
    shadows.light_ssbo.bind_to_storage_buffer(0)
    shadows.view_ssbo.bind_to_storage_buffer(1)
    shadows.polygon_ssbo.bind_to_storage_buffer(2)


def ssbo(ctx, array: np.ndarray):
    """A storage buffer holding `array` (16 zero bytes when it is empty: GL refuses empty buffers)."""
    data = np.ascontiguousarray(array).tobytes()
    return ctx.buffer(data if data else b"\0" * 16)


ZERO_SLAB_BYTES = 32 * 2 ** 20  # a larger volume is zeroed in slabs of whole layers no larger (or of one layer)


def zero_texture(ctx, texture) -> None:
    """Fill `texture` (level 0) with zero bytes from a GPU-side buffer kept on the context (`ctx.extra`), a volume
    in slabs of at most ZERO_SLAB_BYTES.

    Why not `texture.write(bytes(n))`: that builds the zeros in Python and copies them to the GPU every time —
    3.2 GB for the twelve 256³ RGBA32F face volumes of vct_inject, which took 4.6 s of the pass on an H200
    (benchmarks/results/h200). From a buffer object the copy stays on the device (and is faster on llvmpipe too;
    and than a compute pass storing zeros: vct_inject's 48 MiB accumulator at 64³, 4 ms against 32–39 ms).
    """
    depth = getattr(texture, "depth", 1)
    layer = texture.width * texture.height * texture.components * \
        {"f1": 1, "u1": 1, "i1": 1, "f2": 2, "u2": 2, "i2": 2}.get(texture.dtype, 4)
    slab = max(1, min(depth, ZERO_SLAB_BYTES // layer))
    if not isinstance(ctx.extra, dict):
        ctx.extra = {}
    zeros = ctx.extra.get("bounce_gi_zeros")
    if zeros is None or zeros.size < slab * layer:
        if zeros is not None:
            zeros.release()
        zeros = ctx.buffer(reserve=slab * layer)
        zeros.clear()
        ctx.extra["bounce_gi_zeros"] = zeros
    if slab >= depth:
        texture.write(zeros)
        return
    for z in range(0, depth, slab):
        texture.write(zeros, viewport=(0, 0, z, texture.width, texture.height, min(slab, depth - z)))


def texture3d(ctx, size, levels: int = 1, zero: bool = False, dtype: str = "f4"):
    """An RGBA32F volume (RGBA16F with dtype "f2"); `zero`: filled with zeros, so passes may skip storing to empty
    voxels (llvmpipe image stores are slow: storing 12 zeros to every empty voxel took 1 s of vct_inject at 128³)."""
    import moderngl

    t = ctx.texture3d(tuple(int(n) for n in size), 4, None, dtype=dtype)
    if zero:
        zero_texture(ctx, t)
    t.repeat_x = t.repeat_y = t.repeat_z = False
    if levels > 1:
        t.build_mipmaps(0, levels - 1)  # allocates the chain; every level is then overwritten by vct/mipmap.glsl
        t.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    else:
        t.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return t


def read_texture(texture, components: int = 4) -> np.ndarray:
    """RGBA32F texture → (H, W, components) float32 with rows top-to-bottom (image order)."""
    w, h = texture.size
    data = np.frombuffer(texture.read(), np.float32).reshape(h, w, 4)
    return np.ascontiguousarray(data[::-1, :, :components])
