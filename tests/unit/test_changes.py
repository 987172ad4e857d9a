# SPDX-License-Identifier: GPL-3.0-or-later
"""ui/changes.py: depsgraph updates → ChangeSet, driven by small fakes shaped like what bpy 5.2 sends (see the
module's docstring for the batches these copy).

The module is loaded from its file: importing it as bounce_gi.ui.changes would run ui/__init__.py, which imports
bpy, and unit tests run without Blender.
"""
import importlib.util
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "ui" / "changes.py"


def load_changes():
    spec = importlib.util.spec_from_file_location("bounce_gi_ui_changes_under_test", SOURCE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses looks its module up while building ChangeSet
    spec.loader.exec_module(module)
    return module


changes = load_changes()
ChangeSet, change_set = changes.ChangeSet, changes.change_set


class FakeID:
    """An evaluated ID: name, id_type, and `type` (an Object's or node tree's type, a Light's kind)."""

    def __init__(self, name, id_type, type=None, embedded=False):
        self.name, self.id_type, self.type, self.is_embedded_data = name, id_type, type, embedded


class FakeUpdate:
    def __init__(self, id, geometry=False, transform=False, shading=False):
        self.id = id
        self.is_updated_geometry, self.is_updated_transform, self.is_updated_shading = geometry, transform, shading


def obj(name, type, **flags):
    return FakeUpdate(FakeID(name, "OBJECT", type), **flags)


def data(name, id_type, type=None, embedded=False, **flags):
    return FakeUpdate(FakeID(name, id_type, type, embedded), **flags)


ALL = {"geometry": True, "transform": True, "shading": True}
SCENE = data("Scene", "SCENE")


def test_light_move():
    result = change_set([obj("Lamp", "LIGHT", transform=True)])
    assert result == ChangeSet(lights={"Lamp"})
    assert result.gi_dirty and not result.empty


def test_light_colour_edit_names_the_light_object_not_its_data():
    # Light data edit: the light Object (geometry via its data, shading), the Light, its embedded node tree.
    updates = [obj("Lamp", "LIGHT", geometry=True, shading=True), data("Point", "LIGHT", "POINT", **ALL),
               data("Light Node Tree", "NODETREE", "SHADER", embedded=True, **ALL)]
    assert change_set(updates) == ChangeSet(lights={"Lamp"})
    # The Light alone (its object not re-sent): the data's name stands in.
    assert change_set([data("Point", "LIGHT", "POINT", **ALL)]) == ChangeSet(lights={"Point"})


def test_material_edit_is_not_a_geometry_change_of_its_users():
    # Blender re-sends the Object and Mesh using the material with shading only: an echo, not an edit.
    updates = [obj("Cube", "MESH", shading=True), data("CubeMesh", "MESH", shading=True),
               data("Red", "MATERIAL", shading=True), data("Shader Nodetree", "NODETREE", "SHADER", embedded=True)]
    result = change_set(updates)
    assert result == ChangeSet(materials={"Red"})
    assert result.describe() == "material Red"


def test_node_group_and_image_edits_name_the_group_and_image():
    assert change_set([data("Grp", "NODETREE", "SHADER")]) == ChangeSet(materials={"Grp"})
    updates = [obj("Cube", "MESH", shading=True), data("Red", "MATERIAL", shading=True),
               data("Shader Nodetree", "NODETREE", "SHADER", embedded=True), data("Img", "IMAGE", "UV_TEST", **ALL)]
    assert change_set(updates) == ChangeSet(materials={"Red", "Img"})


def test_embedded_node_tree_without_its_owner_is_everything():
    assert change_set([data("Shader Nodetree", "NODETREE", "SHADER", embedded=True)]) == changes.EVERYTHING


def test_object_move_and_empty_move():
    assert change_set([obj("Cube", "MESH", transform=True)]) == ChangeSet(transforms={"Cube"})
    # An animated move also sets shading (Blender flags every animated ID so): still a move.
    assert change_set([obj("Cube", "MESH", transform=True, shading=True)]) == ChangeSet(transforms={"Cube"})
    # A parent empty: its children come as their own updates.
    updates = [obj("Cube", "MESH", transform=True), obj("Rig", "EMPTY", transform=True)]
    assert change_set(updates) == ChangeSet(transforms={"Cube", "Rig"})


def test_geometry_edit_in_edit_mode():
    updates = [obj("Cube", "MESH", geometry=True, shading=True), data("CubeMesh", "MESH", **ALL)]
    assert change_set(updates) == ChangeSet(geometry={"Cube"})
    # A modifier on a moving object: geometry wins over the move.
    assert change_set([obj("Cube", "MESH", **ALL)]) == ChangeSet(geometry={"Cube"})
    # The Mesh alone: its name stands in for the objects using it.
    assert change_set([data("CubeMesh", "MESH", **ALL)]) == ChangeSet(geometry={"CubeMesh"})


def test_shading_only_object_outside_a_material_edit_is_re_extracted():
    # Object colour, ray visibility, material slots: the object's own triangles may carry a new material index.
    assert change_set([obj("Cube", "MESH", shading=True)]) == ChangeSet(geometry={"Cube"})


def test_deformers_reach_the_gi_through_the_objects_they_deform():
    updates = [obj("Cube", "MESH", geometry=True), obj("Lat", "LATTICE", geometry=True, shading=True),
               data("LatD", "LATTICE", **ALL)]
    assert change_set(updates) == ChangeSet(geometry={"Cube"})
    assert change_set([data("GN", "NODETREE", "GEOMETRY"), obj("Cube", "MESH", geometry=True)]) == \
        ChangeSet(geometry={"Cube"})
    assert change_set([data("GN", "NODETREE", "GEOMETRY")]) == changes.NO_CHANGE


def test_camera_move_is_not_gi():
    result = change_set([obj("Camera", "CAMERA", transform=True)], camera_name="Camera")
    assert result == ChangeSet(camera=True)
    assert not result.gi_dirty and not result.empty
    assert result.describe() == "camera"
    # Another camera than the scene's: nothing.
    assert change_set([obj("Side", "CAMERA", transform=True)], camera_name="Camera") == changes.NO_CHANGE
    # A lens change: the camera Object (geometry via its data) and the Camera.
    lens = [obj("Camera", "CAMERA", geometry=True), data("CameraData", "CAMERA", "PERSP", **ALL)]
    assert change_set(lens, camera_name="Camera") == ChangeSet(camera=True)


def test_scene_alone_is_no_change():
    # Selection and many other edits send the Scene alone, without flags.
    result = change_set([SCENE])
    assert result == changes.NO_CHANGE
    assert result.empty and not result.gi_dirty
    assert result.describe() == "no change"


def test_frame_change_is_what_the_animation_moved():
    updates = [SCENE, obj("Cube", "MESH", transform=True, shading=True), data("CubeAction", "ACTION", shading=True)]
    assert change_set(updates) == ChangeSet(transforms={"Cube"})


def test_collection_change_is_visibility():
    # Adding an object: the Scene, every object re-sent with shading only, the new one, a Collection.
    updates = [SCENE, obj("Cube", "MESH", shading=True), obj("Lamp", "LIGHT", shading=True),
               obj("Camera", "CAMERA", shading=True), obj("Plane", "MESH", **ALL), data("PlaneMesh", "MESH", **ALL),
               data("Scene Collection", "COLLECTION", geometry=True, embedded=True)]
    result = change_set(updates)
    assert result == ChangeSet(geometry={"Cube", "Plane"}, lights={"Lamp"}, visibility=True)
    assert result.gi_dirty and result.describe() == "objects added, removed or hidden"
    assert change_set([data("C", "COLLECTION")]) == ChangeSet(visibility=True)


def test_relations_rebuild_without_a_collection_is_visibility():
    # Excluding a collection: the Scene and every remaining object with shading only, no Collection update.
    updates = [SCENE, obj("Cube", "MESH", shading=True), obj("Lamp", "LIGHT", shading=True),
               obj("Camera", "CAMERA", shading=True)]
    assert change_set(updates) == ChangeSet(geometry={"Cube"}, lights={"Lamp"}, visibility=True)
    # Removing an object flags the Scene itself.
    assert change_set([data("Scene", "SCENE", geometry=True, transform=True)]) == ChangeSet(visibility=True)


def test_unknown_types_are_everything_and_harmless_ones_nothing():
    assert change_set([data("Sim", "SIMULATION")]) == changes.EVERYTHING
    assert change_set([obj("Thing", "FUTURE_OBJECT", transform=True)]) == changes.EVERYTHING
    harmless = [data(n, t) for n, t in [("Layout", "SCREEN"), ("WinMan", "WINDOWMANAGER"), ("Notes", "TEXT"),
                                        ("Draw", "BRUSH"), ("Layout", "WORKSPACE"), ("Pal", "PALETTE")]]
    assert change_set(harmless) == changes.NO_CHANGE


def test_world_edit():
    updates = [data("World", "WORLD", **ALL), data("Shader Nodetree", "NODETREE", "SHADER", embedded=True, **ALL)]
    result = change_set(updates)
    assert result == ChangeSet(world=True)
    assert result.gi_dirty and result.describe() == "world"


def test_merged_is_the_union():
    a = ChangeSet(transforms={"Cube"}, lights={"Lamp"}, camera=True)
    b = ChangeSet(transforms={"Ball"}, materials={"Red"}, world=True)
    assert a.merged(b) == ChangeSet(transforms={"Cube", "Ball"}, lights={"Lamp"}, materials={"Red"}, world=True,
                                    camera=True)
    assert changes.NO_CHANGE.merged(a) == a
    assert a.merged(changes.EVERYTHING) == ChangeSet(transforms={"Cube"}, lights={"Lamp"}, camera=True, full=True)


def test_describe():
    assert ChangeSet(lights={"Lamp"}).describe() == "light Lamp changed"
    assert ChangeSet(transforms={"Cube", "Ball"}).describe() == "2 objects moved"
    assert ChangeSet(materials={"Red"}).describe() == "material Red"
    assert ChangeSet(geometry={"Cube"}, materials={"Red", "Blue"}, world=True).describe() == \
        "object Cube edited, 2 materials, world"
    assert changes.EVERYTHING.describe() == "everything"
    assert ChangeSet(transforms={"Cube"}, full=True).describe() == "everything"


def test_id_type_and_name_without_bpy_attributes():
    class SunLight:
        name = "Sun"

    class ShaderNodeTree:
        name = "Grp"

    class Object:
        name = "Cube"

    assert [changes.id_type(c()) for c in (SunLight, ShaderNodeTree, Object)] == ["LIGHT", "NODETREE", "OBJECT"]
    evaluated = FakeID("Cube", "OBJECT", "MESH")
    evaluated.original = FakeID("Cube", "OBJECT", "MESH")
    evaluated.name = "Cube (evaluated copy)"  # never differs in Blender; shows which name is read
    assert changes.id_name(evaluated) == "Cube"


def test_module_does_not_import_bpy():
    code = ("import importlib.util, sys\n"
            f"spec = importlib.util.spec_from_file_location('changes', {str(SOURCE)!r})\n"
            "m = importlib.util.module_from_spec(spec); sys.modules['changes'] = m; spec.loader.exec_module(m)\n"
            "print(sorted(n for n in sys.modules if n.split('.')[0] in ('bpy', '_bpy', 'mathutils')))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"
