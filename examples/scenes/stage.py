# SPDX-License-Identifier: GPL-3.0-or-later
"""The stage: floor, back wall, a cube and a sphere, lit by each kind of light in turn; with a checker texture,
Principled BSDF materials, and shifted and orthographic cameras."""

import math

from mathutils import Vector

from .helpers import (box, camera, checker_image, diffuse_material, light, principled_material, quad,
                      textured_material, uv_sphere)

# Colours (linear Rec.709).
STAGE_WHITE = (0.8, 0.8, 0.8)
STAGE_CUBE = (0.8, 0.3, 0.2)

# Stage light placements, shared by the single-light scenes and light_mixed.
SUN_ROTATION = (math.radians(45.0), 0.0, math.radians(-30.0))
POINT_LOCATION = (1.5, -1.5, 3.0)
SPOT_LOCATION = (-1.0, -2.5, 3.5)
CUBE_LOCATION = (-1.0, 0.0, 0.5)
AREA_LOCATION = (0.0, -1.0, 3.0)
AREA_ROTATION = (math.radians(20.0), 0.0, 0.0)  # faces down, tilted towards the back wall


def _stage(floor_material=None, floor_uv_scale=1.0):
    """Floor 6x6 m, back wall at y=2, a rotated cube and a smooth UV sphere; camera."""
    white = diffuse_material("White", STAGE_WHITE)
    floor_mat = floor_material or white
    quad("Floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1), floor_mat, floor_uv_scale)
    quad("BackWall", [(-3, 2, 0), (3, 2, 0), (3, 2, 3), (-3, 2, 3)], (0, -1, 0), white)
    box("Cube", (1.0, 1.0, 1.0), CUBE_LOCATION, 30.0, diffuse_material("CubeOrange", STAGE_CUBE))
    uv_sphere("Sphere", 0.6, (1.2, -0.3, 0.6), white)


def _stage_camera():
    return camera((0.0, -7.0, 3.2), target=(0.0, 0.0, 0.7), lens=35.0)


def _sun(strength=3.0):
    return light("Sun", "SUN", strength, (0.0, 0.0, 5.0), rotation=SUN_ROTATION, angle=math.radians(0.5))


def _point(power=500.0, radius=0.0, name="PointLight"):
    return light(name, "POINT", power, POINT_LOCATION, shadow_soft_size=radius)


def _spot(power=800.0):
    return light(
        "SpotLight", "SPOT", power, SPOT_LOCATION, target=CUBE_LOCATION,
        spot_size=math.radians(60.0), spot_blend=0.3, shadow_soft_size=0.0,
    )


def _area(power=300.0, shape="SQUARE", size=1.0, name="AreaLight"):
    return light(name, "AREA", power, AREA_LOCATION, rotation=AREA_ROTATION, shape=shape, size=size)


def light_sun():
    """Stage lit by a sun, 3 W/m2, angle 0.5 deg, from the upper left."""
    _stage()
    _stage_camera()
    _sun()


def light_point():
    """Stage lit by a 500 W point light with zero radius (hard shadows)."""
    _stage()
    _stage_camera()
    _point()


def light_point_soft():
    """Stage lit by a 500 W point light with radius 0.25 m (soft shadows)."""
    _stage()
    _stage_camera()
    _point(radius=0.25)


def light_spot():
    """Stage lit by an 800 W spot (60 deg, blend 0.3, radius 0) aimed at the cube."""
    _stage()
    _stage_camera()
    _spot()


def light_area_square():
    """Stage lit by a 1 m square area light, 300 W, tilted 20 deg towards the back wall."""
    _stage()
    _stage_camera()
    _area()


def light_area_disk():
    """Stage lit by a 1.2 m diameter disk area light, 300 W, placed like the square one."""
    _stage()
    _stage_camera()
    _area(shape="DISK", size=1.2)


def light_mixed():
    """Stage with sun 1 W/m2 + point 200 W + spot 400 W + square area 150 W."""
    _stage()
    _stage_camera()
    _sun(1.0)
    _point(200.0)
    _spot(400.0)
    _area(150.0)


def textured():
    """Stage with a checker-textured floor (6x6 checks) lit by the sun.

    The image is 64x64 with 2x2 checks, 32-bit float, colourspace Linear
    Rec.709 (pixel values are the linear albedos), packed; the floor UVs run
    0..3 with REPEAT extension, so the floor shows 6x6 checks.
    """
    img = checker_image()
    _stage(floor_material=textured_material("Checker", img), floor_uv_scale=3.0)
    _stage_camera()
    _sun()


def principled():
    """Stage with Principled BSDF materials (rough floor, glossy sphere, half-metallic cube), lit by the sun.

    Checks the view-dependent Diffuse Color of Principled BSDF (its specular layer takes a share of the base).
    """
    quad("Floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], (0, 0, 1),
         principled_material("RoughFloor", STAGE_WHITE, 0.8))
    quad("BackWall", [(-3, 2, 0), (3, 2, 0), (3, 2, 3), (-3, 2, 3)], (0, -1, 0),
         principled_material("Wall", STAGE_WHITE, 0.5))
    box("Cube", (1.0, 1.0, 1.0), CUBE_LOCATION, 30.0, principled_material("HalfMetal", STAGE_CUBE, 0.4, 0.5))
    uv_sphere("Sphere", 0.6, (1.2, -0.3, 0.6), principled_material("Glossy", STAGE_WHITE, 0.2))
    _stage_camera()
    _sun()


def camera_shift():
    """Stage with a sun; camera rolled 15 deg, shift (0.1, -0.05), sensor fit VERTICAL."""
    _stage()
    _sun()
    cam = camera((0.0, -7.0, 3.2), target=(0.0, 0.0, 0.7), lens=35.0, roll_deg=15.0)
    cam.data.shift_x = 0.1
    cam.data.shift_y = -0.05
    cam.data.sensor_fit = "VERTICAL"


def camera_ortho():
    """Stage with a sun; orthographic camera (ortho_scale 8) looking down at 45 deg."""
    _stage()
    _sun()
    target = Vector((0.0, 0.0, 0.7))
    loc = target + 10.0 * Vector((0.0, -math.cos(math.radians(45)), math.sin(math.radians(45))))
    cam = camera(tuple(loc), target=tuple(target))
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = 8.0
