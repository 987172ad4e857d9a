# SPDX-License-Identifier: GPL-3.0-or-later
"""Which triangles the viewport draws with which shader variant (ui/draw.py, viewport/surface.glsl), in what
order, from one vertex buffer: numpy only, on Blender's main thread at each upload.

A part's variant is (share, flat): how the fragment finds its material's diffuse share D(μ) — CONSTANT (the same
from every view: a vertex attribute), GREY or POLY (a polynomial in μ, common/principled.share_polynomial, where
it fits the table: of one channel where the three are the same, as in every material without a coat tint, or of
three) or TABLE (a texture lookup per pixel) — and whether the triangle's three normals are the same, so the vertex
hands it on flat and the fragment normalizes one vector less. On llvmpipe each is cheaper than the next.
"""
from __future__ import annotations

import numpy as np

from ..gpu_kernels.common.principled import ROWS_PER_MATERIAL
from ..gpu_kernels.surface.mesh import ATTRIBUTES

CONSTANT, GREY, POLY, TABLE = "constant", "grey", "poly", "table"
SHARES = (CONSTANT, GREY, POLY, TABLE)


def share_rows(lut: np.ndarray) -> np.ndarray:
    """(M, S, 4): each material's diffuse-share row of the Principled table (row 0 of its ROWS_PER_MATERIAL:
    rgb D(μ) at μ = k/(S−1), common/principled.glsl), the only one the viewport reads."""
    return np.asarray(lut, np.float32)[0::ROWS_PER_MATERIAL]


def material_shares(rows: np.ndarray, fits=None) -> np.ndarray:
    """(M,) each material's share as an index into SHARES: CONSTANT where D(μ) is the same at every μ (Diffuse
    BSDF, Principled with no specular layer), else where `fits` (M,) bool says a polynomial fits GREY if D's
    three channels are the same, POLY if not, else TABLE."""
    constant = np.all(rows[..., :3] == rows[:, :1, :3], axis=(1, 2))
    grey = np.all(rows[..., :3] == rows[..., :1], axis=(1, 2))
    poly = np.zeros(len(rows), bool) if fits is None else np.asarray(fits, bool)
    return np.select([constant, poly & grey, poly], [0, 1, 2], 3)


def size_order(positions) -> np.ndarray:
    """The triangles (3 corners a row of `positions`), smallest first: sorted by the float bits of their squared
    doubled area, an integer key monotonic in it, 1/256 octave steps (equal keys keep their order). numpy sorts
    16-bit keys in linear time: 2 ms for 100 000 triangles on Blender's main thread, a float sort took 15."""
    corner = np.ascontiguousarray(np.asarray(positions, np.float32).reshape(-1, 3, 3).transpose(2, 1, 0))
    e1, e2 = corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0]  # (xyz, triangle)
    cross = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
    area2 = np.maximum(sum(c * c for c in cross), 0.0).astype(np.float32)
    return np.argsort((area2.view(np.int32) >> 15).astype(np.uint16), kind="stable")


def flat_normals(normals) -> np.ndarray:
    """(T,) bool: the triangles whose three corner normals are the same (interpolating them changes nothing)."""
    n = np.asarray(normals, np.float32).reshape(-1, 3, 3)
    return np.all(n == n[:, :1], axis=(1, 2))


def split_mesh(mesh: dict, rows: np.ndarray, layers: int, fits=None) -> tuple[dict, list]:
    """The triangles (surface/mesh.draw_arrays) as one set of vertex arrays and the parts that draw them,
    [((share, flat), (K, 3) uint32 corner indices, first material)], `layers` materials a part (a 1D array
    texture's layers: 2048 on llvmpipe and what GL 4.3 guarantees; `material` holds the CONSTANT share (rgb) and
    the index within the part (a)). One vertex buffer serves every part: copies per part took longer to make than
    the buffer itself.

    Smallest triangles first, within each part and among the parts (by their largest triangle): they are mostly
    the details in front of the large walls, floors and ground, and a fragment that fails the depth test is not
    shaded — in this order llvmpipe shaded 8-14 % less of a redraw on the example rooms. Any order draws the same
    image, but where coincident surfaces tie in depth."""
    order = size_order(mesh["pos"])
    material = np.clip(np.rint(np.asarray(mesh["mat"])[0::3, 0]).astype(np.int64), 0, len(rows) - 1)
    share = material_shares(rows, fits)[material][order]
    constant = share == 0  # one part: no normal, no table
    flat = flat_normals(mesh["nrm"])[order] | constant
    chunk = np.where(constant, 0, material[order] // layers)
    arrays = {name: np.asarray(mesh[name], np.float32) for name, _ in ATTRIBUTES if name != "mat"}
    per_material = np.concatenate([rows[:, 0, :3], (np.arange(len(rows)) % layers)[:, None]], axis=1)
    arrays["material"] = np.repeat(np.take(per_material.astype(np.float32), material, axis=0), 3, axis=0)
    corners = order.astype(np.uint32)[:, None] * 3 + np.arange(3, dtype=np.uint32)
    groups, inverse = np.unique(np.stack([share, flat, chunk], axis=1), axis=0, return_inverse=True)
    parts = []
    for g, (s, f, c) in enumerate(groups):
        members = np.flatnonzero(inverse.ravel() == g)
        parts.append((members[-1], (SHARES[s], bool(f)), corners[members], int(c) * layers))
    return arrays, [part[1:] for part in sorted(parts, key=lambda part: part[0])]
