# SPDX-License-Identifier: GPL-3.0-or-later
"""Closed rooms where most light arrives by bounces: a spot-lit room and a courtyard lit through a roof opening."""

import math

from .helpers import box, camera, diffuse_material, light, mesh_object, quad, quad_faces


def _room(name_prefix, x0, x1, y0, y1, z0, z1, mats, skip=()):
    """Inward-facing axis-aligned room quads; mats maps wall name -> material."""
    walls = {
        "Floor": ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, 1)),
        "Ceiling": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1)),
        "BackWall": ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, -1, 0)),
        "FrontWall": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, 1, 0)),
        "LeftWall": ([(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (1, 0, 0)),
        "RightWall": ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (-1, 0, 0)),
    }
    for wname, (corners, normal) in walls.items():
        if wname not in skip:
            quad(name_prefix + wname, corners, normal, mats[wname])


def spot_room():
    """Closed 4x4x2.6 m room, white (0.7) with a red right wall, a box, a 600 W
    ceiling spot (70 deg) pointing straight down; camera inside near the front wall."""
    white = diffuse_material("White", (0.7, 0.7, 0.7))
    red = diffuse_material("Red", (0.7, 0.15, 0.1))
    mats = {k: white for k in ("Floor", "Ceiling", "BackWall", "FrontWall", "LeftWall")}
    mats["RightWall"] = red
    _room("", -2.0, 2.0, -2.0, 2.0, 0.0, 2.6, mats)
    box("Box", (0.7, 0.7, 0.7), (0.9, 0.6, 0.35), 20.0, white)
    light(
        "SpotLight", "SPOT", 600.0, (0.0, 0.3, 2.55), rotation=(0.0, 0.0, 0.0),
        spot_size=math.radians(70.0), spot_blend=0.15, shadow_soft_size=0.0,
    )
    camera((-0.3, -1.85, 1.5), target=(0.2, 0.6, 0.5), lens=18.0)


COURTYARD_OPENING = (-1.0, 2.0, -2.5, 0.0)  # roof hole x0, x1, y0, y1 at z=3 (3 x 2.5 m)
COURTYARD_SUN_ROTATION = (math.radians(30.0), 0.0, math.radians(30.0))


def courtyard():
    """6x6 m courtyard, 3 m walls, roof with a 3x2.5 m opening; sun (5 W/m2) enters
    through the opening and lights a patch of floor, the rest is bounce light only."""
    white = diffuse_material("White", (0.7, 0.7, 0.7))
    mats = {k: white for k in ("Floor", "BackWall", "FrontWall", "LeftWall", "RightWall")}
    _room("", -3.0, 3.0, -3.0, 3.0, 0.0, 3.0, mats, skip=("Ceiling",))
    # Roof: four rectangles around the opening, one mesh, facing down (inward).
    ox0, ox1, oy0, oy1 = COURTYARD_OPENING
    z = 3.0
    rects = [
        (-3.0, 3.0, oy1, 3.0),  # behind the opening
        (-3.0, 3.0, -3.0, oy0),  # in front
        (-3.0, ox0, oy0, oy1),  # left
        (ox1, 3.0, oy0, oy1),  # right
    ]
    verts, faces, uvs = quad_faces(
        [([(a, c, z), (b, c, z), (b, d, z), (a, d, z)], (0, 0, -1)) for a, b, c, d in rects]
    )
    mesh_object("Roof", verts, faces, white, uvs=uvs)
    light("Sun", "SUN", 5.0, (0.0, 0.0, 6.0), rotation=COURTYARD_SUN_ROTATION, angle=math.radians(0.5))
    camera((2.7, -2.7, 1.4), target=(-0.6, 0.8, 0.7), lens=16.0)
