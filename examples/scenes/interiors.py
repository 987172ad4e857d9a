# SPDX-License-Identifier: GPL-3.0-or-later
"""Interiors like users': a room with a window under sun and sky, a rug and a poster lying 1 mm off a white floor
and wall under a spot, two rooms behind walls thinner than a voxel, a room lit by an emissive lamp shade, and a
furnished living room (40 objects, image textures, sun and sky, an area light and an emissive lamp).

Principled BSDF throughout, as a new user's materials are. Each is checked against committed Cycles references
(examples/references/, tests/accuracy/test_examples_vs_cycles.py).
"""

import math

import numpy as np

from .helpers import (box, camera, cylinder, emission_material, image_from_array, light, mesh_object,
                      principled_material, quad, quad_faces, set_world, uv_sphere)
from .users import SKY

# The sun of the window scenes: 3 W/m2, 35 deg above the horizon.
WINDOW_SUN_STRENGTH = 3.0
# Shines along +x (slightly +y), down: through a window in a wall at the room's -x side.
SUN_FROM_WEST = (math.radians(55.0), 0.0, math.radians(-75.0))
# Shines along -y (slightly -x), down: through a window in a wall at the room's +y side.
SUN_FROM_NORTH = (math.radians(55.0), 0.0, math.radians(160.0))
RUG_HEIGHT = 0.001  # the rug (and the poster) lie 1 mm off the floor (wall)
THIN_WALL = 0.02  # the walls of `thin_walls`: 2 cm, far thinner than a voxel of any default grid
LAMP_SHADE = {"radius": 0.2, "height": 0.3, "segments": 24}  # a closed cylinder: 92 triangles


def _opening_rects(u0, u1, v0, v1, hole):
    """The (u0, u1, v0, v1) rectangles of a wall [u0, u1] x [v0, v1] around a rectangular hole (below, above,
    left, right of it); empty ones (a door reaching the floor) are left out."""
    hu0, hu1, hv0, hv1 = hole
    rects = [(u0, u1, v0, hv0), (u0, u1, hv1, v1), (u0, hu0, hv0, hv1), (hu1, u1, hv0, hv1)]
    return [r for r in rects if r[1] - r[0] > 1e-9 and r[3] - r[2] > 1e-9]


def _wall_quads(axis, c, u0, u1, v0, v1, normal, hole=None):
    """Single-sided quads of a vertical wall in the plane {axis} = c ('x' or 'y'), spanning u (the other horizontal
    axis) and v (z), facing `normal`, with an optional rectangular hole."""
    rects = _opening_rects(u0, u1, v0, v1, hole) if hole else [(u0, u1, v0, v1)]

    def p(u, v):
        return (c, u, v) if axis == "x" else (u, c, v)

    return [([p(a, cc), p(b, cc), p(b, d), p(a, d)], normal) for a, b, cc, d in rects]


def _box_wall(name, axis, c, u0, u1, v0, v1, thickness, material, hole=None):
    """A solid wall `thickness` thick centred on the plane {axis} = c, as boxes around an optional hole."""
    rects = _opening_rects(u0, u1, v0, v1, hole) if hole else [(u0, u1, v0, v1)]
    for i, (a, b, cc, d) in enumerate(rects):
        size = (thickness, b - a, d - cc) if axis == "x" else (b - a, thickness, d - cc)
        loc = (c, (a + b) / 2, (cc + d) / 2) if axis == "x" else ((a + b) / 2, c, (cc + d) / 2)
        box(f"{name}{i}", size, loc, 0.0, material)


def _shell(x0, x1, y0, y1, z1, mats, window=None):
    """A closed room of single-sided quads facing inward, one object per surface; mats: name -> material;
    window = (wall name, hole) cuts a hole (u0, u1, z0, z1) into that wall."""
    walls = {"LeftWall": ("x", x0, y0, y1, (1, 0, 0)), "RightWall": ("x", x1, y0, y1, (-1, 0, 0)),
             "FrontWall": ("y", y0, x0, x1, (0, 1, 0)), "BackWall": ("y", y1, x0, x1, (0, -1, 0))}
    quad("Floor", [(x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0)], (0, 0, 1), mats["Floor"],
         mats.get("floor_uv_scale", 1.0))
    quad("Ceiling", [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1), mats["Ceiling"])
    for name, (axis, c, u0, u1, normal) in walls.items():
        hole = window[1] if window and window[0] == name else None
        verts, faces, uvs = quad_faces(_wall_quads(axis, c, u0, u1, 0.0, z1, normal, hole))
        mesh_object(name, verts, faces, mats.get(name, mats["Walls"]), uvs=uvs)


def _sofa(prefix, x, y, width, material, rotation=0.0):
    """A sofa of four boxes (seat, back, two arms) facing -y (rotation 0) or rotated about z by `rotation` deg."""
    import mathutils

    rot = mathutils.Matrix.Rotation(math.radians(rotation), 3, "Z")
    parts = {"Seat": ((width, 0.85, 0.42), (0.0, 0.0, 0.21)), "Back": ((width, 0.2, 0.45), (0.0, 0.33, 0.645)),
             "ArmL": ((0.18, 0.85, 0.22), (-width / 2 + 0.09, 0.0, 0.53)),
             "ArmR": ((0.18, 0.85, 0.22), (width / 2 - 0.09, 0.0, 0.53))}
    for name, (size, offset) in parts.items():
        o = rot @ mathutils.Vector(offset)
        box(prefix + name, size, (x + o.x, y + o.y, o.z), rotation, material)


def window_room():
    """A 4 x 5 x 2.7 m room (single-sided walls, like most users' rooms) with a 1.6 x 1.2 m window in its left
    wall; the sun (3 W/m2, 35 deg up) shines through it onto the floor and a constant sky (strength 1) lights the
    room through it; a sofa, a low table and a cabinet. Principled BSDF (walls roughness 0.7, a wooden floor)."""
    walls = principled_material("Walls", (0.8, 0.78, 0.74), roughness=0.7)
    floor = principled_material("WoodFloor", (0.35, 0.2, 0.1), roughness=0.4)
    _shell(-2.0, 2.0, -2.5, 2.5, 2.7, {"Floor": floor, "Ceiling": walls, "Walls": walls},
           window=("LeftWall", (-0.6, 1.0, 0.9, 2.1)))
    _sofa("Sofa", 0.6, 2.0, 2.0, principled_material("Fabric", (0.3, 0.35, 0.5), roughness=1.0))
    box("LowTable", (1.0, 0.6, 0.4), (0.6, 0.6, 0.2), 0.0, principled_material("Oak", (0.45, 0.3, 0.15), 0.5))
    box("Cabinet", (0.5, 1.2, 0.9), (1.7, -1.2, 0.45), 0.0, principled_material("WhiteGloss", (0.8, 0.8, 0.8), 0.2))
    light("Sun", "SUN", WINDOW_SUN_STRENGTH, (-5.0, 0.0, 5.0), rotation=SUN_FROM_WEST, angle=math.radians(0.5))
    set_world(SKY, 1.0)
    camera((1.75, -2.3, 1.5), target=(-1.2, 0.6, 0.9), lens=18.0)


def rug_room():
    """A closed 4 x 4 x 2.6 m white room (Principled, base 0.8) with a red rug lying 1 mm above the floor and a
    blue poster 1 mm off the back wall, lit by an 800 W ceiling spot (60 deg, blend 0.2) aimed at the rug."""
    white = principled_material("White", (0.8, 0.8, 0.8), roughness=0.6)
    _shell(-2.0, 2.0, -2.0, 2.0, 2.6, {"Floor": white, "Ceiling": white, "Walls": white})
    h = RUG_HEIGHT
    quad("Rug", [(-1.0, -0.4, h), (1.0, -0.4, h), (1.0, 1.2, h), (-1.0, 1.2, h)], (0, 0, 1),
         principled_material("RedRug", (0.7, 0.1, 0.05), roughness=1.0))
    quad("Poster", [(-0.6, 2.0 - h, 1.0), (0.6, 2.0 - h, 1.0), (0.6, 2.0 - h, 1.8), (-0.6, 2.0 - h, 1.8)],
         (0, -1, 0), principled_material("BluePoster", (0.05, 0.2, 0.6), roughness=0.8))
    box("Box", (0.5, 0.5, 0.5), (1.3, 1.2, 0.25), 15.0, white)
    light("Spot", "SPOT", 800.0, (0.0, -0.6, 2.55), target=(0.0, 0.4, 0.0), spot_size=math.radians(60.0),
          spot_blend=0.2, shadow_soft_size=0.0)
    camera((-0.3, -1.85, 1.5), target=(0.2, 0.6, 0.4), lens=18.0)


def thin_walls():
    """Two 4 x 4 x 2.6 m rooms side by side, every wall, the floor and the ceiling a solid slab 2 cm thick
    (thinner than a voxel), the partition with a 0.9 x 2 m door. Sun (3 W/m2) and sky (strength 1) enter room A
    through a window in its west wall; room B, where the camera stands, has a north window the sun does not reach
    (only the sky and the light through the door). Any light through the walls, the floor or the roof shows.
    Walls in matte paint (Principled, Specular IOR Level 0, a common "pure diffuse" set-up), the floor in default
    Principled."""
    t = THIN_WALL
    paint = principled_material("MattePaint", (0.8, 0.8, 0.78), specular_level=0.0)
    floor = principled_material("Floor", (0.5, 0.4, 0.3))
    x0, x1, y0, y1, z1 = -4.0, 4.0, -2.0, 2.0, 2.6
    box("FloorSlab", (x1 - x0 + 2 * t, y1 - y0 + 2 * t, t), (0.0, 0.0, -t / 2), 0.0, floor)
    box("CeilingSlab", (x1 - x0 + 2 * t, y1 - y0 + 2 * t, t), (0.0, 0.0, z1 + t / 2), 0.0, paint)
    _box_wall("WestWall", "x", x0 - t / 2, y0, y1, 0.0, z1, t, paint, hole=(-0.8, 0.8, 0.9, 2.0))
    _box_wall("EastWall", "x", x1 + t / 2, y0, y1, 0.0, z1, t, paint)
    _box_wall("SouthWall", "y", y0 - t / 2, x0 - t, x1 + t, 0.0, z1, t, paint)
    _box_wall("NorthWall", "y", y1 + t / 2, x0 - t, x1 + t, 0.0, z1, t, paint, hole=(1.5, 3.0, 1.0, 2.0))
    _box_wall("Partition", "x", 0.0, y0, y1, 0.0, z1, t, paint, hole=(-0.45, 0.45, 0.0, 2.0))
    box("BoxA", (0.6, 0.6, 0.6), (-2.0, 1.0, 0.3), 20.0, principled_material("Teal", (0.1, 0.45, 0.45)))
    box("BoxB", (0.8, 0.5, 0.9), (2.5, 1.3, 0.45), -10.0, principled_material("Ochre", (0.7, 0.5, 0.15)))
    light("Sun", "SUN", WINDOW_SUN_STRENGTH, (-6.0, 0.0, 5.0), rotation=SUN_FROM_WEST, angle=math.radians(0.5))
    set_world(SKY, 1.0)
    camera((3.6, -1.7, 1.5), target=(-1.5, 0.4, 0.9), lens=20.0)


def _floor_lamp(prefix, x, y, shade_material, metal):
    """Base, pole and a closed-cylinder shade (LAMP_SHADE) at 1.4-1.7 m: the emissive lamp of the lamp scenes."""
    cylinder(prefix + "Base", 0.15, 0.03, (x, y, 0.015), metal)
    cylinder(prefix + "Pole", 0.015, 1.4, (x, y, 0.73), metal, segments=8)
    s = LAMP_SHADE
    cylinder(prefix + "Shade", s["radius"], s["height"], (x, y, 1.4 + s["height"] / 2), shade_material,
             segments=s["segments"])


def lamp_room():
    """A 4 x 4 x 2.6 m room lit only by a floor lamp whose shade glows: a closed cylinder (24 segments, 92
    triangles, radius 0.2 m, 0.3 m tall) in Principled BSDF with emission (warm white, strength 30); a sofa, a side
    table and a box; black world."""
    walls = principled_material("Walls", (0.8, 0.78, 0.74), roughness=0.7)
    floor = principled_material("WoodFloor", (0.35, 0.2, 0.1), roughness=0.4)
    _shell(-2.0, 2.0, -2.0, 2.0, 2.6, {"Floor": floor, "Ceiling": walls, "Walls": walls})
    shade = principled_material("GlowingShade", (0.9, 0.85, 0.75), roughness=0.8, emission=(1.0, 0.8, 0.55),
                                emission_strength=30.0)
    steel = principled_material("Steel", (0.56, 0.57, 0.58), 0.3, metallic=1.0)
    _floor_lamp("Lamp", -1.4, 1.4, shade, steel)
    _sofa("Sofa", 0.3, 1.5, 1.8, principled_material("Fabric", (0.45, 0.2, 0.15), roughness=1.0))
    box("SideTable", (0.45, 0.45, 0.5), (-1.4, 0.6, 0.25), 0.0, principled_material("Oak", (0.45, 0.3, 0.15), 0.5))
    box("Box", (0.5, 0.5, 0.5), (1.3, -0.6, 0.25), 25.0, walls)
    camera((1.7, -1.8, 1.4), target=(-0.8, 0.8, 0.9), lens=20.0)


def _planks_image():
    """64 x 64 wooden planks: 8 rows of tone-varied strips (linear colours)."""
    rng = np.random.default_rng(17)
    rows = np.repeat(rng.uniform(0.75, 1.15, 8), 8)[:, None]  # one tone per plank row
    grain = 1.0 + 0.08 * np.sin(np.linspace(0, 12 * math.pi, 64))[None, :]
    tone = rows * grain
    rgb = np.stack([0.42 * tone, 0.26 * tone, 0.13 * tone], axis=-1)
    rgb[::8] *= 0.5  # the gaps between planks
    return image_from_array("Planks", rgb)


def _painting_image():
    """24 x 32 colour blocks (a painting)."""
    rgb = np.empty((24, 32, 3))
    rgb[:] = (0.7, 0.6, 0.3)
    rgb[:12, :16] = (0.1, 0.2, 0.5)
    rgb[12:, 16:] = (0.6, 0.1, 0.08)
    rgb[6:18, 10:22] = (0.8, 0.8, 0.75)
    return image_from_array("Painting", rgb)


def furnished():
    """A furnished 6 x 5 x 2.7 m living room, 40 objects: wooden plank floor (an image texture), a sofa and an
    armchair, a coffee table, a rug 1 mm above the floor, a bookshelf with books, a TV on a stand, a plant, a
    painting (an image texture) 2 mm off its frame, a floor lamp whose shade is an Emission shader (strength 15).
    Sun (3 W/m2) and sky (strength 1) through a 1.6 x 1.3 m window in the back wall, and a 1 m ceiling area light
    (100 W). Principled BSDF throughout."""
    walls = principled_material("Walls", (0.8, 0.78, 0.74), roughness=0.7)
    planks = principled_material("Planks", (1.0, 1.0, 1.0), roughness=0.4, image=_planks_image())
    _shell(-3.0, 3.0, -2.5, 2.5, 2.7, {"Floor": planks, "floor_uv_scale": 3.0, "Ceiling": walls, "Walls": walls},
           window=("BackWall", (-1.8, -0.2, 0.9, 2.2)))
    fabric = principled_material("Fabric", (0.25, 0.3, 0.45), roughness=1.0)
    oak = principled_material("Oak", (0.45, 0.3, 0.15), roughness=0.5)
    dark = principled_material("DarkWood", (0.12, 0.07, 0.04), roughness=0.4)
    _sofa("Sofa", -0.8, -1.9, 2.2, fabric, rotation=180.0)
    _sofa("Armchair", 2.2, -0.3, 0.9, fabric, rotation=-90.0)
    box("TableTop", (1.2, 0.7, 0.05), (-0.8, -0.5, 0.42), 0.0, oak)
    for i, (dx, dy) in enumerate(((-0.55, -0.3), (0.55, -0.3), (-0.55, 0.3), (0.55, 0.3))):
        box(f"TableLeg{i}", (0.05, 0.05, 0.4), (-0.8 + dx, -0.5 + dy, 0.2), 0.0, oak)
    quad("Rug", [(-2.0, -1.4, 0.001), (0.4, -1.4, 0.001), (0.4, 0.4, 0.001), (-2.0, 0.4, 0.001)], (0, 0, 1),
         principled_material("RugWool", (0.6, 0.5, 0.3), roughness=1.0))
    # Bookshelf against the left wall: two sides, four shelves, six books.
    for i, y in enumerate((0.3, 1.5)):
        box(f"ShelfSide{i}", (0.35, 0.03, 1.8), (-2.8, y, 0.9), 0.0, dark)
    for i in range(4):
        box(f"Shelf{i}", (0.35, 1.2, 0.03), (-2.8, 0.9, 0.1 + 0.55 * i), 0.0, dark)
    book_colors = ((0.6, 0.1, 0.1), (0.1, 0.3, 0.6), (0.7, 0.6, 0.2), (0.2, 0.5, 0.2), (0.8, 0.8, 0.75),
                   (0.3, 0.1, 0.4))
    for i, c in enumerate(book_colors):
        shelf, k = divmod(i, 3)
        box(f"Book{i}", (0.22, 0.06, 0.28), (-2.8, 0.5 + 0.3 * k, 0.26 + 0.55 * (shelf + 1)), 0.0,
            principled_material(f"Book{i}", c, roughness=0.6))
    box("TvStand", (1.4, 0.4, 0.5), (0.8, 2.25, 0.25), 0.0, dark)
    box("Tv", (1.1, 0.05, 0.65), (0.8, 2.3, 0.825), 0.0, principled_material("Screen", (0.02, 0.02, 0.02), 0.1))
    cylinder("PlantPot", 0.18, 0.35, (2.6, 2.1, 0.175), principled_material("Terracotta", (0.6, 0.3, 0.18), 0.8))
    uv_sphere("Plant", 0.35, (2.6, 2.1, 0.7), principled_material("Leaves", (0.1, 0.35, 0.08), 0.7), segments=12,
              rings=8)
    box("PaintingFrame", (0.01, 1.7, 1.1), (2.995, -0.4, 1.6), 0.0, dark)  # x 2.99-3.0, on the right wall
    x = 2.99 - 0.002  # the painting: 2 mm in front of its frame
    quad("Painting", [(x, -1.15, 1.1), (x, 0.35, 1.1), (x, 0.35, 2.1), (x, -1.15, 2.1)], (-1, 0, 0),
         principled_material("Painting", (1.0, 1.0, 1.0), 0.6, image=_painting_image()))
    steel = principled_material("Steel", (0.56, 0.57, 0.58), 0.3, metallic=1.0)
    _floor_lamp("Lamp", -2.6, -2.1, emission_material("LampShade", (1.0, 0.8, 0.55), 15.0), steel)
    light("Sun", "SUN", WINDOW_SUN_STRENGTH, (0.0, 6.0, 5.0), rotation=SUN_FROM_NORTH, angle=math.radians(0.5))
    light("CeilingLight", "AREA", 100.0, (0.0, 0.0, 2.68), rotation=(0.0, 0.0, 0.0), shape="SQUARE", size=1.0)
    set_world(SKY, 1.0)
    camera((2.7, -2.3, 1.6), target=(-1.0, 1.0, 0.8), lens=18.0)
