# SPDX-License-Identifier: GPL-3.0-or-later
"""The GPU side's only input: a scene as plain dataclasses and numpy arrays.

Everything here is in Blender's world space (metres, Z up) and Blender's units (docs/conventions.md).
`addon/extract/` builds it from a depsgraph; tests and examples may build it by hand. No bpy.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, fields, is_dataclass, replace
from functools import lru_cache

import numpy as np

LIGHT_TYPES = ("SUN", "POINT", "SPOT", "AREA")
AREA_SHAPES = ("SQUARE", "RECTANGLE", "DISK", "ELLIPSE")


@dataclass
class Texture:
    """An RGB(A) image in scene-linear float, rows bottom-up (OpenGL/Blender order)."""
    name: str
    pixels: np.ndarray  # (H, W, 4) float32
    interpolation: str = "Linear"  # "Linear" | "Closest"
    extension: str = "REPEAT"  # "REPEAT" | "EXTEND" | "CLIP"


@dataclass
class Material:
    """What the pipeline understands of a material; extraction reduces node trees to this."""
    name: str
    base_color: tuple = (0.8, 0.8, 0.8)  # linear RGB, the diffuse albedo when no texture
    base_color_texture: int = -1  # index into Scene.textures, or -1
    emission: tuple = (0.0, 0.0, 0.0)  # emission colour × strength (radiance, W/(m²·sr) per unit)
    roughness: float = 0.5
    metallic: float = 0.0
    specular_layer: bool = False  # Principled BSDF: the layers below weigh the diffuse base (common/principled.py)
    # Principled inputs that set the layers' albedo (Cycles' meaning and defaults):
    ior: float = 1.5
    specular_ior_level: float = 0.5  # 0: no dielectric specular layer; 0.5: F0 of the IOR; 1: twice that F0
    specular_tint: tuple = (1.0, 1.0, 1.0)
    transmission: float = 0.0
    coat_weight: float = 0.0
    coat_roughness: float = 0.03
    coat_ior: float = 1.5
    coat_tint: tuple = (1.0, 1.0, 1.0)
    multiscatter: bool = True  # distribution Multiscatter GGX (Principled's default) rather than GGX


@dataclass
class Light:
    """A Blender light in Cycles' meaning (docs/conventions.md); `color` already includes energy-independent tint."""
    name: str
    type: str  # one of LIGHT_TYPES
    color: tuple  # linear RGB tint (temperature applied), not including power
    power: float  # W for POINT/SPOT/AREA; irradiance W/m² for SUN (strength)
    matrix_world: np.ndarray  # (4, 4) float64; the light shines along its local -Z
    radius: float = 0.0  # point/spot soft size (m)
    angle: float = 0.0  # sun angular diameter (rad)
    spot_size: float = np.pi / 4  # full cone angle (rad)
    spot_blend: float = 0.15
    shape: str = "SQUARE"  # area shape
    size: float = 1.0  # area size along local X (m)
    size_y: float = 1.0  # area size along local Y (m), RECTANGLE/ELLIPSE
    soft_falloff: bool = True  # Blender 4+: a radius-r point/spot acts as a disk facing the receiver, E ∝ 1/(d²+r²)
    cast_shadow: bool = True

    @property
    def position(self) -> np.ndarray:
        return np.asarray(self.matrix_world, np.float64)[:3, 3].copy()

    @property
    def direction(self) -> np.ndarray:
        """Unit vector the light points along (local -Z in world space)."""
        d = -np.asarray(self.matrix_world, np.float64)[:3, 2]
        return d / np.linalg.norm(d)


@dataclass
class Camera:
    """Blender camera data needed to reproduce its projection pixel for pixel."""
    matrix_world: np.ndarray  # (4, 4) camera-to-world; camera looks along local -Z, +Y up
    type: str = "PERSP"  # "PERSP" | "ORTHO"
    lens: float = 50.0  # mm
    sensor_width: float = 36.0  # mm
    sensor_height: float = 24.0  # mm
    sensor_fit: str = "AUTO"  # "AUTO" | "HORIZONTAL" | "VERTICAL"
    ortho_scale: float = 7.0
    shift_x: float = 0.0
    shift_y: float = 0.0
    clip_start: float = 0.1
    clip_end: float = 100.0


@dataclass
class World:
    color: tuple = (0.0, 0.0, 0.0)  # constant background radiance = colour × strength


@dataclass
class Scene:
    """Triangle soup in world space plus materials, lights, world and camera.

    positions: (T, 3, 3) float32 — triangle corners
    normals:   (T, 3, 3) float32 — per-corner shading normals as Blender shows them
    uvs:       (T, 3, 2) float32 — per-corner UVs (zeros when the mesh has none)
    material_index: (T,) int32 — index into `materials`
    """
    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    material_index: np.ndarray
    materials: list = field(default_factory=list)
    textures: list = field(default_factory=list)
    lights: list = field(default_factory=list)
    world: World = field(default_factory=World)
    camera: Camera | None = None
    resolution: tuple = (640, 480)  # the scene's render resolution (after percentage)
    pixel_aspect: tuple = (1.0, 1.0)
    warnings: list = field(default_factory=list)

    @property
    def triangle_count(self) -> int:
        return int(self.positions.shape[0])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned world bounds of all triangles (min, max). Found once per positions array (kept beside the
        fields, not in them: hashing and copies see only the fields): a render asks a dozen times (every light's
        views, the grids, the memory check), each a pass over every corner. A scene's positions are replaced, not
        changed in place, once it has been rendered."""
        memo = self.__dict__.get("_bounds")
        if memo is None or memo[0] is not self.positions:
            if self.triangle_count == 0:
                found = np.zeros(3), np.zeros(3)
            else:
                p = self.positions.reshape(-1, 3)
                found = p.min(axis=0).astype(np.float64), p.max(axis=0).astype(np.float64)
            memo = self.__dict__["_bounds"] = (self.positions, found)
        return memo[1][0].copy(), memo[1][1].copy()

    def surface_arrays(self) -> tuple:
        """What a rasterised surface is made of: positions, normals, UVs and material indices (the geometry's key;
        what a kept map or output records it was drawn from, direct/shadows.moved_box)."""
        return self.positions, self.normals, self.uvs, self.material_index

    def has_emission(self) -> bool:
        used = set(np.unique(self.material_index).tolist()) if self.triangle_count else set()
        return any(max(self.materials[i].emission) > 0 for i in used if 0 <= i < len(self.materials))

    def statistics(self) -> dict:
        lo, hi = self.bounds()
        return {
            "triangles": self.triangle_count,
            "materials": len(self.materials),
            "textures": len(self.textures),
            "lights": {t: sum(1 for l in self.lights if l.type == t) for t in LIGHT_TYPES},
            "bounds": [lo.tolist(), hi.tolist()],
        }

    def content_hash(self) -> str:
        """A stable hash of everything that affects a render (used to key reference caches)."""
        h = hashlib.sha256()
        _hash_into(h, self)
        return h.hexdigest()[:20]


def material_keys(scene: Scene) -> dict:
    """Content keys of the materials by what reads them: "materials" (everything: the G-buffer, the voxels),
    "textures" (which materials take their base colour from which image, and the images: what the LPV's RSM holds),
    "layers" (the Principled layers without any colour: the material table, common/principled.material_lut),
    "emission" (the emissive triangles' radiance: the lights and shadow maps) and "shading" (what direct light reads
    of a surface beyond its position: the layers, and the base colour only where a metal's Fresnel takes it — a
    dielectric's base colour only tints the Diffuse Color that compose multiplies by). A base colour edit of a
    non-metal changes "materials" alone."""
    metals = [i for i, m in enumerate(scene.materials) if m.metallic != 0]
    textures = hash_parts([m.base_color_texture for m in scene.materials], scene.textures)
    layers = hash_parts([replace(m, name="", emission=(0.0, 0.0, 0.0), base_color=(0.0, 0.0, 0.0))
                         for m in scene.materials])
    return {"materials": hash_parts(scene.materials, textures), "textures": textures, "layers": layers,
            "emission": hash_parts([m.emission for m in scene.materials]),
            "shading": hash_parts(layers, [scene.materials[i].base_color for i in metals],
                                  textures if metals else None)}


def finite_normals(positions: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """`normals` with every non-finite or zero corner normal replaced by its triangle's geometric normal (a mesh
    with broken custom normals still shades; the winding says which side is the front), and by +Z where the
    triangle has no area either (a zero-area triangle covers nothing, but its normal still enters sums)."""
    bad = ~np.isfinite(normals).all(axis=-1) | (np.abs(normals).sum(axis=-1) == 0)
    if not bad.any():
        return normals
    p = positions.astype(np.float64)
    geo = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(geo, axis=-1, keepdims=True)
    geo = np.where(length > 0, geo / np.maximum(length, 1e-300), (0.0, 0.0, 1.0))
    out = normals.copy()
    out[bad] = np.broadcast_to(geo[:, None, :], normals.shape)[bad]
    return out


def hash_parts(*parts) -> str:
    """A SHA-1 of `parts` (arrays, dataclasses, lists, numbers, strings): the content keys of the pass cache."""
    h = hashlib.sha1()
    for p in parts:
        _hash_into(h, p)
    return h.hexdigest()


def _hash_into(h, value) -> None:
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    elif is_dataclass(value):
        kind, names = _field_names(type(value))
        h.update(kind)
        for name, encoded in names:
            h.update(encoded)
            _hash_into(h, getattr(value, name))
    elif isinstance(value, (list, tuple)):
        h.update(b"[")
        for v in value:
            _hash_into(h, v)
        h.update(b"]")
    elif isinstance(value, float):
        h.update(repr(round(value, 9)).encode())
    else:
        h.update(repr(value).encode())


@lru_cache(maxsize=None)
def _field_names(cls) -> tuple:
    """A dataclass's name and its fields' (name, encoded name) but "warnings", as _hash_into feeds them: computed
    once per class (fields() per instance was most of an unchanged frame's key hashing)."""
    return cls.__name__.encode(), tuple((f.name, f.name.encode()) for f in fields(cls) if f.name != "warnings")
