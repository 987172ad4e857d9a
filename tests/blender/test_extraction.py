# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender → Scene extraction (addon/extract/) checked against Blender's own numbers.

All bpy work runs in ONE subprocess (tests/support/extraction_probe.py), so Blender state never leaks into the
pytest process. The subprocess builds example scenes, extracts them with `extract_scene`, computes the same
quantities independently through bpy (evaluated meshes, object instances, light data) and writes a JSON summary.
Each experiment is recorded separately: one that raises stores its traceback, and only the tests that need it fail.
"""
import os

import numpy as np
import pytest

from support.bpy_summary import run_summary

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PROBE = os.path.join(ROOT, "tests", "support", "extraction_probe.py")  # the bpy side, run in the subprocess

# Known construction of the `extraction` example (examples/scenes/extraction_scene.py::extraction), in triangles.
CUBE_QUADS = 6
SUBSURF_LEVELS = 2
BLOB_TRIS = 2 * CUBE_QUADS * 4 ** SUBSURF_LEVELS * 2  # mirrored cube, each quad -> 4^levels quads -> 2 triangles
SEGMENTS = 24
CONE_TRIS = SEGMENTS + (SEGMENTS - 2)  # side fan + triangulated base n-gon
CYLINDER_TRIS = 2 * SEGMENTS + 2 * (SEGMENTS - 2)  # side quads + two triangulated caps
PROPS_INSTANCES = 3  # each instances the Cone and the Cylinder: 6 object instances
PLANE_TRIS = 2
GROUND_TRIS = 2
EXTRACTION_TRIS = BLOB_TRIS + PROPS_INSTANCES * (CONE_TRIS + CYLINDER_TRIS) + PLANE_TRIS + GROUND_TRIS


@pytest.fixture(scope="module")
def data():
    return run_summary(PROBE, lambda out, tmp: [out], ROOT, {"BOUNCE_GI_CACHE": os.path.join("{tmp}", "cache")})


def get(data, key):
    """One experiment's record; fail with its traceback if it raised."""
    rec = data[key]
    if isinstance(rec, dict) and set(rec) == {"error"}:
        pytest.fail(f"experiment '{key}' raised in the bpy subprocess:\n{rec['error']}")
    return rec


def unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def face_normals(positions):
    p = np.asarray(positions, np.float64)
    return unit(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))


# ---- geometry


def test_triangle_count_matches_blender(data):
    e = get(data, "extraction")
    assert e["triangles"] == e["blender"]["triangles"], e["blender"]["per_object"]
    assert e["statistics"]["triangles"] == e["triangles"]


def test_triangle_count_matches_construction(data):
    e = get(data, "extraction")
    per = e["blender"]["per_object"]
    assert per == {"Ground": GROUND_TRIS, "Blob": BLOB_TRIS, "Cone": PROPS_INSTANCES * CONE_TRIS,
                   "Cylinder": PROPS_INSTANCES * CYLINDER_TRIS, "CustomNormals": PLANE_TRIS}
    assert e["triangles"] == EXTRACTION_TRIS


def test_world_bounds_match_blender(data):
    e = get(data, "extraction")
    np.testing.assert_allclose(e["bounds"], e["blender"]["bounds"], atol=1e-5)
    np.testing.assert_allclose(e["statistics"]["bounds"], e["blender"]["bounds"], atol=1e-5)
    # The 8x8 m ground spans x, y; the tallest thing is the 1.5x-scaled 0.8 m prop (1.2 m).
    np.testing.assert_allclose(e["bounds"][0], (-4, -4, 0), atol=1e-5)
    np.testing.assert_allclose(e["bounds"][1], (4, 4, 1.2), atol=1e-5)


def test_extraction_has_no_warnings(data):
    assert get(data, "extraction")["warnings"] == []


def test_custom_normals_survive(data):
    e = get(data, "extraction")
    n = np.asarray(e["plane_normals"]).reshape(-1, 3)
    assert n.shape == (3 * PLANE_TRIS, 3)
    m = np.asarray(e["plane_matrix"])[:3, :3]
    expected = unit(m @ np.asarray(e["custom_normal"]))  # the plane is only translated
    # Blender stores custom normals in a compressed form (~3e-5 from the exact vector), hence 1e-4 here;
    # against Blender's own evaluated corner normals the match is 1e-5 (next test).
    np.testing.assert_allclose(n, np.broadcast_to(expected, n.shape), atol=1e-4)


def test_custom_normals_follow_rotation_and_scale(data):
    e = get(data, "extraction")
    n = np.asarray(e["moved_plane_normals"]).reshape(-1, 3)
    m = np.asarray(e["moved_plane_matrix"])[:3, :3]
    normal_matrix = np.linalg.inv(m).T
    blender = unit(np.asarray(e["blender_corner_normals"]).reshape(-1, 3) @ normal_matrix.T)  # in world space
    assert n.shape == blender.shape == (3 * PLANE_TRIS, 3)
    np.testing.assert_allclose(n, blender, atol=1e-5)
    np.testing.assert_allclose(n, np.broadcast_to(unit(normal_matrix @ e["custom_normal"]), n.shape), atol=1e-4)
    # The shading normal and the winding agree (the plane faces up, so do its normals).
    g = face_normals(e["moved_plane_positions"])
    assert np.all(np.einsum("tj,tcj->tc", g, n.reshape(-1, 3, 3)) > 0)


def test_smooth_sphere_has_smooth_normals(data):
    s = get(data, "stage")
    p, n = np.asarray(s["positions"]), np.asarray(s["normals"])
    c, r = np.asarray(s["sphere_center"]), s["sphere_radius"]
    on_sphere = np.all(np.linalg.norm(p - c, axis=-1) < r + 1e-4, axis=1)
    assert on_sphere.sum() == s["sphere_tris"]
    p, n = p[on_sphere], n[on_sphere]
    radial = unit(p - c)
    assert np.einsum("tcj,tcj->tc", n, radial).min() > 0.99  # smooth normals point away from the centre
    spread = np.linalg.norm(n - n[:, :1], axis=-1).max(axis=1)
    assert np.mean(spread > 1e-3) > 0.9, "the corners of a smooth triangle should carry different normals"


def test_flat_cube_has_face_normals(data):
    s = get(data, "stage")
    p, n = np.asarray(s["cube_positions"]), np.asarray(s["cube_normals"])
    assert p.shape == (12, 3, 3)
    g = face_normals(p)
    np.testing.assert_allclose(n, np.broadcast_to(g[:, None], n.shape), atol=1e-5)
    outward = unit(p.mean(axis=1) - s["cube_center"])
    assert np.all(np.einsum("tj,tj->t", g, outward) > 0)


def test_mirrored_object_keeps_winding_and_normals_consistent(data):
    s = get(data, "stage")
    p, n = np.asarray(s["mirrored_cube_positions"]), np.asarray(s["mirrored_cube_normals"])
    assert p.shape == (12, 3, 3)
    g = face_normals(p)
    np.testing.assert_allclose(n, np.broadcast_to(g[:, None], n.shape), atol=1e-5)
    outward = unit(p.mean(axis=1) - s["cube_center"])
    assert np.all(np.einsum("tj,tj->t", g, outward) > 0), "mirrored cube faces point inwards"
    # A mirrored plane (custom normals, no symmetry to hide mistakes).
    e = get(data, "extraction")
    p, n = np.asarray(e["mirrored_plane_positions"]), np.asarray(e["mirrored_plane_normals"])
    g = face_normals(p)
    np.testing.assert_allclose(g, np.broadcast_to((0, 0, 1), g.shape), atol=1e-6)
    assert np.all(np.einsum("tj,tcj->tc", g, n) > 0)
    m = np.asarray(e["mirrored_plane_matrix"])[:3, :3]
    expected = unit(np.linalg.inv(m).T @ e["custom_normal"])  # (-1, 0, 1)/sqrt(2)
    np.testing.assert_allclose(n.reshape(-1, 3), np.broadcast_to(expected, (n.size // 3, 3)), atol=1e-4)


def test_hide_render_objects_are_skipped(data):
    s = get(data, "stage")
    assert s["hidden_triangles"] == s["triangles"] - s["sphere_tris"]
    assert s["hidden_triangles"] == s["hidden_blender"]["triangles"]
    p = np.asarray(s["hidden_positions"])
    near_sphere = np.all(np.linalg.norm(p - s["sphere_center"], axis=-1) < s["sphere_radius"] + 1e-4, axis=1)
    assert not near_sphere.any()


def test_textured_floor_uvs(data):
    t = get(data, "textured")
    uv = np.asarray(t["floor_uvs"])
    assert uv.shape == (2, 3, 2)
    assert uv.min() >= 0.0 and uv.max() <= 3.0
    np.testing.assert_allclose([uv.min(), uv.max()], [0.0, 3.0], atol=1e-6)  # the floor UVs run 0..3


# ---- materials


def test_texture_is_read_linear(data):
    t = get(data, "textured")
    (tex,) = t["textures"]
    w, h = t["image_size"]
    assert tex["name"] == "Checker" and tex["shape"] == [h, w, 4] and tex["dtype"] == "float32"
    assert (tex["interpolation"], tex["extension"]) == ("Linear", "REPEAT")
    colors = np.asarray(tex["colors"])
    assert len(colors) == 2
    assert any(np.allclose(c, (0.8, 0.8, 0.8), atol=1e-6) for c in colors), colors
    assert any(np.allclose(c, (0.1, 0.3, 0.7), atol=1e-6) for c in colors), colors
    checker = t["materials"]["Checker"]
    assert checker["texture"] == 0 and checker["base_color"] == [1.0, 1.0, 1.0]


def test_diffuse_material(data):
    m = get(data, "textured")["materials"]["White"]
    assert m["base_color"] == pytest.approx([0.8, 0.8, 0.8], abs=1e-6)
    assert m["texture"] == -1 and m["roughness"] == 1.0 and m["metallic"] == 0.0
    assert not m["specular_layer"] and m["emission"] == [0.0, 0.0, 0.0]


def test_principled_material(data):
    r = get(data, "materials")
    m = r["materials"]["PrincipledTest"]
    assert "PrincipledTest" in r["used"]
    assert m["specular_layer"] and m["texture"] == -1
    assert m["base_color"] == pytest.approx([0.2, 0.4, 0.6], abs=1e-6)
    assert m["roughness"] == pytest.approx(0.35, abs=1e-6) and m["metallic"] == pytest.approx(0.1, abs=1e-6)
    assert not any("PrincipledTest" in w for w in r["warnings"]), r["warnings"]


def test_unsupported_material_falls_back_to_viewport_colour(data):
    r = get(data, "materials")
    m = r["materials"]["GlassTest"]
    assert "GlassTest" in r["used"]
    assert m["base_color"] == pytest.approx(r["glass_viewport"], abs=1e-6)
    assert m["texture"] == -1 and m["emission"] == [0.0, 0.0, 0.0]
    named = [w for w in r["warnings"] if "GlassTest" in w]
    assert len(named) == 1, r["warnings"]


def test_camera_less_scene_raises_extract_error(data):
    r = get(data, "no_camera")
    assert r["raised"] == "ExtractError", r
    assert "camera" in r["message"]


# ---- lights


LIGHT_SCENES = ["light_sun", "light_point", "light_point_soft", "light_spot", "light_area_square",
                "light_area_disk", "light_mixed"]


@pytest.mark.parametrize("name", LIGHT_SCENES)
def test_lights_match_blender(data, name):
    rec = get(data, "lights")[name]
    theirs, ours = rec["bpy"], rec["ours"]
    assert sorted(ours) == sorted(theirs) and theirs
    for lname, b in theirs.items():
        o = ours[lname]
        assert o["type"] == b["type"], lname
        assert o["power"] == pytest.approx(b["energy"], rel=1e-6), lname
        assert o["color"] == pytest.approx(b["color"], abs=1e-6), lname
        np.testing.assert_allclose(o["matrix"], b["matrix"], atol=1e-6, err_msg=lname)
        np.testing.assert_allclose(o["direction"], b["direction"], atol=1e-6, err_msg=lname)
        if b["type"] in ("POINT", "SPOT"):
            assert o["radius"] == pytest.approx(b["radius"], abs=1e-7), lname
        if b["type"] == "SPOT":
            assert (o["spot_size"], o["spot_blend"]) == pytest.approx((b["spot_size"], b["spot_blend"])), lname
        if b["type"] == "SUN":
            assert o["angle"] == pytest.approx(b["angle"]), lname
        if b["type"] == "AREA":
            assert o["shape"] == b["shape"], lname
            assert (o["size"], o["size_y"]) == pytest.approx((b["size"], b["size_y"])), lname


def test_all_light_scenes_covered(data):
    assert sorted(get(data, "lights")) == sorted(LIGHT_SCENES)


def test_light_exposure_doubles_power(data):
    r = get(data, "light_settings")
    assert r["base"]["power"] == pytest.approx(r["energy"])
    assert r["exposed"]["power"] == pytest.approx(2.0 * r["energy"])
    assert r["exposed"]["color"] == pytest.approx(r["base"]["color"])


def test_light_temperature_tints_colour(data):
    r = get(data, "light_settings")
    tc = np.asarray(r["temperature_color"])
    assert not np.allclose(tc, 1.0), "3000 K should not be white"
    assert r["warm"]["color"] == pytest.approx((np.asarray(r["color"]) * tc).tolist(), rel=1e-6)
    assert r["warm"]["power"] == pytest.approx(r["energy"])
