# SPDX-License-Identifier: GPL-3.0-or-later
"""The Cornell box: lit by a square area light (`cornell`) or by an emissive ceiling panel (`cornell_emissive`)."""

import math

from .helpers import box, camera, diffuse_material, emission_material, light, mesh_object, quad, quad_faces

# Colours (linear Rec.709).
CORNELL_WHITE = (0.725, 0.71, 0.68)
CORNELL_RED = (0.63, 0.065, 0.05)
CORNELL_GREEN = (0.14, 0.45, 0.091)


def _cornell_geometry(ceiling_hole=0.0):
    """Walls, boxes and camera. ceiling_hole > 0 leaves a centred square opening
    of that size in the ceiling (for a flush emissive panel)."""
    white = diffuse_material("White", CORNELL_WHITE)
    red = diffuse_material("Red", CORNELL_RED)
    green = diffuse_material("Green", CORNELL_GREEN)
    x0, x1, y0, y1, z0, z1 = -1.0, 1.0, -1.0, 1.0, 0.0, 2.0
    quad("Floor", [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, 1), white)
    if ceiling_hole > 0:
        h = ceiling_hole / 2
        rects = [(x0, x1, h, y1), (x0, x1, y0, -h), (x0, -h, -h, h), (h, x1, -h, h)]
        verts, faces, uvs = quad_faces(
            [([(a, c, z1), (b, c, z1), (b, d, z1), (a, d, z1)], (0, 0, -1)) for a, b, c, d in rects]
        )
        mesh_object("Ceiling", verts, faces, white, uvs=uvs)
    else:
        quad("Ceiling", [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1), white)
    quad("BackWall", [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, -1, 0), white)
    quad("LeftWall", [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (1, 0, 0), red)
    quad("RightWall", [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (-1, 0, 0), green)
    # Proportions of the classic box (552.8 units -> 2 m).
    box("TallBox", (0.6, 0.6, 1.2), (-0.33, 0.28, 0.6), 17.0, white)
    box("ShortBox", (0.6, 0.6, 0.6), (0.34, -0.32, 0.3), -17.0, white)
    camera((0.0, -3.9, 1.0), rotation=(math.radians(90.0), 0.0, 0.0), lens=38.0)


CORNELL_LIGHT_SIZE = 0.5
CORNELL_LIGHT_POWER = 60.0
# Cycles: an area light of power P and area A has radiance P / (pi * A); an
# Emission shader of strength S has radiance S. So 60 W over 0.25 m^2 matches
# strength 240 / pi = 76.39. The emissive scene uses 10 (as specified), i.e.
# 7.64x dimmer than `cornell`.
CORNELL_EMISSION_STRENGTH = 10.0


def cornell():
    """Classic Cornell box lit by a 0.5 m square area light, 60 W, at z=1.98 facing down."""
    _cornell_geometry()
    light(
        "AreaLight", "AREA", CORNELL_LIGHT_POWER, (0.0, 0.0, 1.98), rotation=(0.0, 0.0, 0.0),
        shape="SQUARE", size=CORNELL_LIGHT_SIZE,
    )


def cornell_emissive():
    """Cornell box lit by an emissive 0.5 m quad (Emission, white, strength 10).

    The panel sits flush in a matching opening of the ceiling (z=2, facing
    down), so the light Cycles emits from its back side leaves the box and the
    panel acts as a one-sided emitter with zero albedo.
    """
    _cornell_geometry(ceiling_hole=CORNELL_LIGHT_SIZE)
    h = CORNELL_LIGHT_SIZE / 2
    z = 2.0
    quad(
        "LightPanel",
        [(-h, -h, z), (h, -h, z), (h, h, z), (-h, h, z)],
        (0, 0, -1),
        emission_material("Emitter", (1.0, 1.0, 1.0), CORNELL_EMISSION_STRENGTH),
    )
