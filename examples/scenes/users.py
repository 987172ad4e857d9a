# SPDX-License-Identifier: GPL-3.0-or-later
"""Scenes like users' first scenes (not rooms): Blender's default material everywhere, metals, many point lights, a
large outdoor scene and a small product shot. Principled BSDF throughout, as a new user's materials are.

Each is checked against committed Cycles references (examples/references/, tests/accuracy/test_examples_vs_cycles.py).
"""

import math

from .helpers import (DEFAULT_BASE, box, camera, cylinder, lathe, light, mesh_object, principled_material, quad,
                      quad_faces, set_world, uv_sphere)

# A constant sky (linear Rec.709) at strength 1, the world of the sun-and-sky scenes.
SKY = (0.45, 0.6, 0.85)
BRASS = (0.91, 0.78, 0.42)  # brass's reflectance at normal incidence, as a metallic base colour


def default_principled():
    """A room corner (floor, two walls), a table, a cube and a sphere, all in Blender's default Principled BSDF
    (base 0.8, roughness 0.5, IOR 1.5, Specular IOR Level 0.5: one shared material, as a new user's scene has), and
    a brass vase (the same material with metallic 1 and a brass colour). Lit by a 1 m square area light, 100 W."""
    mat = principled_material("Material")  # Blender's default, unchanged
    quad("Floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1), mat)
    quad("BackWall", [(-3, 2, 0), (3, 2, 0), (3, 2, 3), (-3, 2, 3)], (0, -1, 0), mat)
    quad("LeftWall", [(-2.5, -3, 0), (-2.5, 2, 0), (-2.5, 2, 3), (-2.5, -3, 3)], (1, 0, 0), mat)
    box("TableTop", (1.6, 0.9, 0.06), (0.3, 0.6, 0.75), 0.0, mat)
    for i, (dx, dy) in enumerate(((-0.72, -0.38), (0.72, -0.38), (-0.72, 0.38), (0.72, 0.38))):
        box(f"TableLeg{i}", (0.06, 0.06, 0.72), (0.3 + dx, 0.6 + dy, 0.36), 0.0, mat)
    box("Cube", (0.7, 0.7, 0.7), (-1.4, -0.2, 0.35), 25.0, mat)
    uv_sphere("Sphere", 0.35, (1.6, -0.6, 0.35), mat)
    brass = principled_material("Brass", BRASS, metallic=1.0)
    profile = [(0.08, 0.0), (0.13, 0.06), (0.15, 0.14), (0.12, 0.24), (0.07, 0.32), (0.06, 0.38), (0.08, 0.42)]
    lathe("Vase", profile, (0.5, 0.6, 0.78), brass)
    light("AreaLight", "AREA", 100.0, (0.8, -1.2, 2.6), target=(0.2, 0.5, 0.6), shape="SQUARE", size=1.0)
    camera((1.2, -4.6, 1.9), target=(-0.1, 0.4, 0.6), lens=30.0)


def metals():
    """Metals on a grey floor against a back wall: gold, copper, steel and aluminium spheres (roughness 0.25 /
    0.35 / 0.15 / 0.5) and a brushed-steel box, lit by two area lights (key 300 W, fill 80 W); black world."""
    floor = principled_material("GreyFloor", (0.5, 0.5, 0.5), roughness=0.6)
    wall = principled_material("Wall", (0.7, 0.68, 0.64), roughness=0.8)
    quad("Floor", [(-4, -4, 0), (4, -4, 0), (4, 3, 0), (-4, 3, 0)], (0, 0, 1), floor)
    quad("BackWall", [(-4, 2.5, 0), (4, 2.5, 0), (4, 2.5, 3.5), (-4, 2.5, 3.5)], (0, -1, 0), wall)
    metal = {"Gold": ((1.0, 0.77, 0.34), 0.25), "Copper": ((0.95, 0.64, 0.54), 0.35),
             "Steel": ((0.56, 0.57, 0.58), 0.15), "Aluminium": ((0.91, 0.92, 0.92), 0.5)}
    for i, (name, (color, rough)) in enumerate(metal.items()):
        uv_sphere(name + "Sphere", 0.45, (-1.8 + 1.2 * i, 0.2, 0.45), principled_material(name, color, rough,
                                                                                          metallic=1.0))
    box("SteelBox", (0.8, 0.8, 0.8), (0.2, 1.4, 0.4), 30.0,
        principled_material("BrushedSteel", (0.56, 0.57, 0.58), 0.4, metallic=1.0))
    light("KeyLight", "AREA", 300.0, (-2.0, -2.5, 3.0), target=(0.0, 0.5, 0.4), shape="SQUARE", size=1.5)
    light("FillLight", "AREA", 80.0, (3.0, -2.0, 1.5), target=(0.0, 0.5, 0.4), shape="RECTANGLE", size=2.0,
          size_y=1.0)
    camera((0.0, -5.5, 2.0), target=(0.0, 0.5, 0.45), lens=35.0)


def many_lights():
    """A hall 12 x 4 x 3 m with a row of pillars and 20 point lights (two rows of 10 under the ceiling, 12 W each,
    radius 0.1 m, warm and cool white alternating); walls, floor and pillars in Principled BSDF."""
    walls = principled_material("HallWalls", (0.75, 0.72, 0.68), roughness=0.7)
    floor = principled_material("HallFloor", (0.35, 0.3, 0.26), roughness=0.4)
    x0, x1, y0, y1, z1 = -2.0, 2.0, -6.0, 6.0, 3.0
    quad("Floor", [(x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0)], (0, 0, 1), floor)
    verts, faces, uvs = quad_faces([
        ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1)),
        ([(x0, y1, 0), (x1, y1, 0), (x1, y1, z1), (x0, y1, z1)], (0, -1, 0)),
        ([(x0, y0, 0), (x1, y0, 0), (x1, y0, z1), (x0, y0, z1)], (0, 1, 0)),
        ([(x0, y0, 0), (x0, y1, 0), (x0, y1, z1), (x0, y0, z1)], (1, 0, 0)),
        ([(x1, y0, 0), (x1, y1, 0), (x1, y1, z1), (x1, y0, z1)], (-1, 0, 0)),
    ])
    mesh_object("HallShell", verts, faces, walls, uvs=uvs)
    for i in range(5):
        box(f"Pillar{i}", (0.35, 0.35, z1), (0.0, -4.0 + 2.0 * i, z1 / 2), 0.0, walls)
    warm, cool = (1.0, 0.85, 0.7), (0.8, 0.9, 1.0)
    for i in range(10):
        for j, x in enumerate((-1.1, 1.1)):
            light(f"Point{i}_{j}", "POINT", 12.0, (x, -5.4 + 1.2 * i, 2.7), color=warm if (i + j) % 2 else cool,
                  shadow_soft_size=0.1)
    camera((1.3, -5.7, 1.6), target=(-0.3, 2.0, 1.0), lens=22.0)


def outdoor():
    """A town block 200 m across under sun (4 W/m2, 40 deg up) and a constant sky (strength 1): a ground plane,
    a road, nine buildings 6-24 m tall, trees (trunk and crown); the camera stands at eye height in the street."""
    ground = principled_material("Grass", (0.18, 0.28, 0.1), roughness=0.9)
    asphalt = principled_material("Asphalt", (0.12, 0.12, 0.12), roughness=0.8)
    facade = [principled_material(f"Facade{i}", c, roughness=0.7) for i, c in
              enumerate(((0.75, 0.7, 0.62), (0.6, 0.35, 0.25), (0.8, 0.8, 0.8)))]
    bark = principled_material("Bark", (0.25, 0.17, 0.1), roughness=0.9)
    leaves = principled_material("Leaves", (0.1, 0.35, 0.08), roughness=0.7)
    quad("Ground", [(-100, -100, 0), (100, -100, 0), (100, 100, 0), (-100, 100, 0)], (0, 0, 1), ground)
    quad("Road", [(-5, -100, 0.02), (5, -100, 0.02), (5, 100, 0.02), (-5, 100, 0.02)], (0, 0, 1), asphalt)
    blocks = [((-14, -20), (10, 14, 12)), ((-14, 2), (10, 16, 20)), ((-16, 26), (12, 14, 8)),
              ((14, -24), (10, 12, 6)), ((15, -4), (12, 14, 24)), ((14, 20), (10, 12, 15)),
              ((-40, 50), (20, 16, 18)), ((35, 60), (16, 20, 10)), ((0, 80), (30, 12, 14))]
    for i, ((x, y), (sx, sy, sz)) in enumerate(blocks):
        box(f"Building{i}", (sx, sy, sz), (x, y, sz / 2), 0.0, facade[i % 3])
    for i, (x, y) in enumerate(((-7, -30), (7, -14), (-7, -6), (7, 8), (-7, 16), (7, 34))):
        cylinder(f"Trunk{i}", 0.25, 3.0, (x, y, 1.5), bark, segments=8)
        uv_sphere(f"Crown{i}", 2.0, (x, y, 4.2), leaves, segments=12, rings=6)
    light("Sun", "SUN", 4.0, (0, 0, 50), rotation=(math.radians(50.0), 0.0, math.radians(-35.0)),
          angle=math.radians(0.5))
    set_world(SKY, 1.0)
    cam = camera((2.0, -55.0, 1.7), target=(-2.0, 10.0, 6.0), lens=24.0)
    cam.data.clip_end = 500.0


def product_shot():
    """A product shot 10 cm across: a curved white backdrop (a sweep, 10 x 8 cm), a glossy red bottle 5 cm tall with
    a steel cap, a small matte sphere and a brass coin; two small area lights (key 5 cm, 0.06 W; fill 0.02 W)."""
    sweep = principled_material("Backdrop", (0.85, 0.85, 0.85), roughness=0.6)
    w, depth, height, r = 0.05, 0.04, 0.06, 0.02  # half width, floor depth from the front edge, back height, bend
    profile = [(-depth, 0.0), (0.0, 0.0)]  # (y, z) from the front edge to the back, bending up over radius r
    for k in range(1, 7):
        a = math.radians(90.0 * k / 6)
        profile.append((r * math.sin(a), r * (1 - math.cos(a))))
    profile.append((r, height))
    verts = [(x, y + 0.02, z) for y, z in profile for x in (-w, w)]
    faces = [(2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2) for i in range(len(profile) - 1)]
    mesh_object("Backdrop", verts, faces, sweep, smooth=True)
    cylinder("Bottle", 0.012, 0.045, (-0.012, 0.0, 0.0225), principled_material("RedGlossy", (0.6, 0.05, 0.04),
                                                                                roughness=0.2))
    cylinder("Cap", 0.007, 0.01, (-0.012, 0.0, 0.05), principled_material("CapSteel", (0.56, 0.57, 0.58), 0.3,
                                                                         metallic=1.0))
    uv_sphere("Ball", 0.009, (0.018, -0.012, 0.009), principled_material("MatteBlue", (0.1, 0.25, 0.6), 0.9))
    coin = principled_material("BrassCoin", BRASS, 0.3, metallic=1.0)
    cylinder("Coin", 0.008, 0.003, (0.02, 0.012, 0.0015), coin)
    light("Key", "AREA", 0.06, (-0.045, -0.04, 0.07), target=(0.0, 0.0, 0.02), shape="SQUARE", size=0.05)
    light("Fill", "AREA", 0.02, (0.05, -0.03, 0.04), target=(0.0, 0.0, 0.02), shape="SQUARE", size=0.04)
    cam = camera((0.0, -0.3, 0.09), target=(0.0, 0.0, 0.02), lens=85.0)
    cam.data.clip_start = 0.01


__all__ = ["SKY", "BRASS", "DEFAULT_BASE", "default_principled", "metals", "many_lights", "outdoor",
           "product_shot"]
