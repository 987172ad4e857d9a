# SPDX-License-Identifier: GPL-3.0-or-later
"""What changed in the scene, for the viewport's GI: `change_set(depsgraph.updates)` → a `ChangeSet`.

`RenderEngine.view_update(context, depsgraph)` sees one `DepsgraphUpdate` per data-block Blender re-evaluated: its
`id` (the evaluated copy; `id.original` is the data-block in the file, with the same name) and three flags,
`is_updated_geometry`, `is_updated_transform` and `is_updated_shading`. The flags are per ID, not per object:
an Object's geometry flag is also set when its data (mesh, light, camera) changed, and the shading flag is also
set by animation (Blender sets it for every animated ID on a frame change). This module sorts those updates into
the parts of the GI the engine can refresh on their own, and says "everything" (`full`) for whatever it cannot
sort safely. It imports no bpy and reads IDs by duck typing, so tests drive it with small fakes.

What Blender sends, as seen with bpy 5.2 (`depsgraph_update_post`, whose depsgraph has the same `updates`):
    moving an object          that Object, transform
    editing a mesh            its Object (geometry, shading) and the Mesh (all three)
    a light's colour / power  the light Object (geometry, shading), the Light, the light's embedded node tree
    a material or its nodes   the Material, its embedded node tree, and every Object and Mesh using it with
                              shading only (an echo: their geometry did not change)
    a world                   the World and its embedded node tree
    selecting; hiding with H  the Scene alone, no flags: the two cannot be told apart from here
    adding, removing, linking the Scene, a Collection, and every object of the view layer with shading only
    excluding a collection,   the Scene and every object with shading only (no Collection): the echo of
    switching camera / world  Blender rebuilding its relations
    a frame change            the Scene, every animated ID, their Actions
Lattices, armatures, shape keys, geometry-node trees and the like reach the render only through the objects they
deform, and Blender re-sends those objects with their own geometry flag; they are ignored here.

Hiding objects with H (or hiding a view layer's collection) sends only the Scene, exactly like a selection
click, so it does not show here: a caller that must catch it compares the set of visible objects itself.
"""
from dataclasses import dataclass, fields

# Object types that extraction turns into triangles. EMPTY joins them for moves: it may instance a collection,
# whose objects do not come as updates of their own when only the empty moves.
MESH_LIKE = frozenset({"MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES", "POINTCLOUD", "VOLUME"})
MOVABLE = MESH_LIKE | {"EMPTY"}
# Object types that are not rendered and act only through the objects they deform.
PASSIVE_OBJECTS = frozenset({"ARMATURE", "LATTICE", "SPEAKER", "LIGHT_PROBE", "GREASEPENCIL"})
# ID types of object data that holds geometry (a text object's data is a CURVE; FONT is the font file).
GEOMETRY_DATA = frozenset({"MESH", "CURVE", "META", "CURVES", "POINTCLOUD", "VOLUME"})
# Edits of these make Blender re-send every object using them with the shading flag only.
SHADING_SOURCES = frozenset({"MATERIAL", "NODETREE", "IMAGE"})
# The IDs that own an embedded shader node tree: an edit of the tree re-sends its owner too.
NODE_TREE_OWNERS = frozenset({"MATERIAL", "WORLD", "LIGHT"})
# ID types whose effect on the render arrives as updates of the objects that depend on them.
DRIVERS = frozenset({"ACTION", "ANIMATION", "ARMATURE", "LATTICE", "KEY", "PARTICLE", "CACHEFILE", "FONT",
                     "TEXTURE"})
# ID types that cannot affect light: UI, editing tools, sound, compositing, EEVEE-only and unrendered data.
IRRELEVANT = frozenset({"SCREEN", "WINDOWMANAGER", "WORKSPACE", "TEXT", "BRUSH", "PALETTE", "PAINTCURVE", "SOUND",
                        "SPEAKER", "MASK", "LINESTYLE", "LIBRARY", "LIGHT_PROBE", "MOVIECLIP", "GREASEPENCIL",
                        "GREASEPENCIL_V3"})
IGNORED = DRIVERS | IRRELEVANT

# id_type from the class name, for IDs without `id_type`: exact names first, then suffixes (PointLight, SunLight,
# ShaderNodeTree, ImageTexture...), else the upper-cased class name (Object → OBJECT, WorkSpace → WORKSPACE).
CLASS_IDS = {"MetaBall": "META", "VectorFont": "FONT", "ParticleSettings": "PARTICLE", "LightProbe": "LIGHT_PROBE",
             "FreestyleLineStyle": "LINESTYLE", "GreasePencilv3": "GREASEPENCIL_V3"}
CLASS_SUFFIXES = (("NodeTree", "NODETREE"), ("Light", "LIGHT"), ("Texture", "TEXTURE"))
NAME_FIELDS = ("geometry", "transforms", "materials", "lights")


@dataclass(frozen=True)
class ChangeSet:
    """One batch of scene changes, sorted by what the GI must redo. Name sets may be given as any iterable."""
    geometry: frozenset = frozenset()    # objects whose triangles changed: mesh edits, modifiers, material slots
    transforms: frozenset = frozenset()  # mesh-like objects and empties that moved, their geometry unchanged
    # Materials whose shading changed. A node group's or an image's name stands for every material (and world)
    # that uses it: a caller that cannot map a name to a material re-reads all of them.
    materials: frozenset = frozenset()
    lights: frozenset = frozenset()      # light objects moved or edited (a Light's name when its object is absent)
    world: bool = False
    camera: bool = False                 # the scene camera moved or its lens changed: F12, not the viewport GI
    visibility: bool = False             # objects added, removed, (un)linked or excluded: re-extract everything
    full: bool = False                   # something this module cannot sort: re-extract everything

    def __post_init__(self):
        for name in NAME_FIELDS:
            object.__setattr__(self, name, frozenset(getattr(self, name)))

    @property
    def gi_dirty(self) -> bool:
        """Whether the view-independent GI depends on anything that changed (all but a camera-only change)."""
        return any(getattr(self, f.name) for f in fields(self) if f.name != "camera")

    @property
    def empty(self) -> bool:
        return not any(getattr(self, f.name) for f in fields(self))

    def merged(self, other: "ChangeSet") -> "ChangeSet":
        """Both change sets in one: for updates that arrive before the job that handles them starts."""
        return ChangeSet(*(getattr(self, f.name) | getattr(other, f.name) for f in fields(self)))

    def describe(self) -> str:
        """One short line for the panel: "object Cube moved", "2 lights changed, material Red", "everything"."""
        if self.full:
            return "everything"
        if self.visibility:
            return "objects added, removed or hidden"
        parts = [phrase(self.geometry, "object", "objects", "edited"), phrase(self.transforms, "object", "objects",
                 "moved"), phrase(self.lights, "light", "lights", "changed"), phrase(self.materials, "material",
                 "materials"), "world" if self.world else "", "camera" if self.camera else ""]
        return ", ".join(p for p in parts if p) or "no change"


NO_CHANGE = ChangeSet()
EVERYTHING = ChangeSet(full=True)


def phrase(names, one: str, many: str, verb: str = "") -> str:
    """One name: "object Cube moved"; more: "3 objects moved"; none: "" (left out of the line)."""
    if not names:
        return ""
    text = f"{one} {next(iter(names))}" if len(names) == 1 else f"{len(names)} {many}"
    return f"{text} {verb}".rstrip()


def id_type(id_) -> str:
    """The ID's type as Blender's `ID.id_type` names it ('OBJECT', 'MESH', 'LIGHT', 'NODETREE', ...), from the
    class name when the ID has no `id_type`."""
    kind = getattr(id_, "id_type", None)
    if isinstance(kind, str) and kind:
        return kind
    cls = type(id_).__name__
    if cls in CLASS_IDS:
        return CLASS_IDS[cls]
    for suffix, kind in CLASS_SUFFIXES:
        if cls.endswith(suffix):
            return kind
    return cls.upper()


def id_name(id_) -> str:
    """The name of the original data-block (an evaluated copy has the same name)."""
    original = getattr(id_, "original", None)
    return (id_ if original is None else original).name


def update_flags(update) -> tuple[bool, bool, bool]:
    """(geometry, transform, shading) of one DepsgraphUpdate."""
    return (bool(getattr(update, "is_updated_geometry", False)), bool(getattr(update, "is_updated_transform", False)),
            bool(getattr(update, "is_updated_shading", False)))


class Collector:
    """The change set being built from one batch of updates (`kinds`: every id_type in the batch)."""

    def __init__(self, kinds: set, camera_name):
        self.kinds, self.camera_name = kinds, camera_name
        self.echo = bool(kinds & SHADING_SOURCES)  # shading-only object updates may be a material edit's echo
        self.names = {name: set() for name in NAME_FIELDS}
        self.data_geometry, self.data_lights = set(), set()  # data names, used only where no object came
        self.flags = {"world": False, "camera": False, "visibility": False, "full": False}
        self.scene = False        # a Scene update came (alone: selection, frame, H-hiding: nothing to do)
        self.unexplained = False  # an object came with shading only, not as a material edit's echo

    def add(self, update) -> None:
        kind, name = id_type(update.id), id_name(update.id)
        geometry, transform, shading = update_flags(update)
        if kind == "OBJECT":
            self.add_object(update.id, name, geometry, transform)
        elif kind == "SCENE":
            self.scene = True
            self.flags["visibility"] |= geometry or transform  # Blender sets them when objects are removed
        elif kind == "COLLECTION":
            self.flags["visibility"] = True
        elif kind in GEOMETRY_DATA:
            if geometry or not self.echo:
                self.data_geometry.add(name)
        elif kind == "LIGHT":
            self.data_lights.add(name)
        elif kind in ("MATERIAL", "IMAGE"):
            self.names["materials"].add(name)
        elif kind == "NODETREE":
            self.add_node_tree(update.id, name)
        elif kind == "WORLD":
            self.flags["world"] = True
        elif kind == "CAMERA":
            self.flags["camera"] = True
        elif kind not in IGNORED:
            self.flags["full"] = True

    def add_object(self, obj, name: str, geometry: bool, transform: bool) -> None:
        """One Object update. Shading only (or no flag) on a mesh-like object outside a material edit is a change
        of that object's own shading: its colour, ray visibility or material slots. Slots set the material index
        of its triangles, so the object goes to `geometry`: re-extracting one object is cheap and always right.
        Inside a material edit (a Material, shader node tree or Image in the batch) it is the edit's echo."""
        kind = getattr(obj, "type", None)
        moved_or_edited = geometry or transform
        if not moved_or_edited and not (kind in MOVABLE and self.echo):
            self.unexplained = True
        if kind in MOVABLE:
            if geometry or not (transform or self.echo):
                self.names["geometry"].add(name)
            elif transform:
                self.names["transforms"].add(name)
        elif kind == "LIGHT":
            self.names["lights"].add(name)
        elif kind == "CAMERA":
            if moved_or_edited and self.camera_name in (None, name):
                self.flags["camera"] = True
        elif kind not in PASSIVE_OBJECTS:
            self.flags["full"] = True

    def add_node_tree(self, tree, name: str) -> None:
        """Shader trees only: geometry-node trees reach the render as geometry updates of the objects using them,
        compositing and texture trees not at all. An embedded tree (a material's, world's or light's own) comes
        with its owner; without one in the batch the owner is unknown, so everything is redone."""
        if getattr(tree, "type", None) not in (None, "SHADER"):
            return
        if getattr(tree, "is_embedded_data", False):
            self.flags["full"] |= not self.kinds & NODE_TREE_OWNERS
            return
        self.names["materials"].add(name)

    def result(self) -> ChangeSet:
        """The change set. Data names stand in for objects only when no object of that kind came (Blender sends
        the objects of edited data, so normally they are not needed). The Scene together with objects that came
        with shading only, unexplained, is Blender rebuilding relations: visibility changed."""
        flags = dict(self.flags, visibility=self.flags["visibility"] or (self.scene and self.unexplained))
        names = dict(self.names, geometry=self.names["geometry"] or self.data_geometry,
                     lights=self.names["lights"] or self.data_lights)
        return ChangeSet(**names, **flags)


def change_set(updates, camera_name: str | None = None) -> ChangeSet:
    """Sort `depsgraph.updates` (any iterable of objects with `id` and the three `is_updated_*` flags) into a
    ChangeSet. `camera_name`: the scene camera's object name; None counts a move of any camera."""
    updates = list(updates)
    collector = Collector({id_type(u.id) for u in updates}, camera_name)
    for update in updates:
        collector.add(update)
    return collector.result()


__all__ = ["ChangeSet", "EVERYTHING", "NO_CHANGE", "change_set", "id_name", "id_type"]
