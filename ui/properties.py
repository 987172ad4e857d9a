"""Per-scene settings, stored in the .blend as `bpy.types.Scene.bounce_gi`.

Only user choices live here. Results of the last render are runtime state (see operators.py)
so that a preview never dirties or bloats the file.
"""
import bpy
from bpy.props import EnumProperty, IntProperty, StringProperty
from bpy.types import PropertyGroup

# Identifiers are upper case (Blender convention); the engine wants lower case (method_id()).
METHOD_ITEMS = (
    ("NONE", "Direct only", "Direct light with shadow maps, no indirect bounce"),
    ("LPV", "Light Propagation Volumes", "Indirect light propagated through a grid of SH coefficients"),
    ("VCT", "Voxel Cone Tracing", "Indirect light gathered by tracing cones through a voxel mip chain"),
)


class BounceGISettings(PropertyGroup):
    """What the Render Preview operator renders and where batch renders are written."""

    method: EnumProperty(
        name="Method",
        description="How indirect (bounced) light is computed",
        items=METHOD_ITEMS,
        default="NONE",
    )
    resolution_percentage: IntProperty(
        name="Resolution",
        description="Preview size as a percentage of the scene's render resolution",
        subtype="PERCENTAGE",
        min=10,
        max=100,
        default=50,
    )
    output_path: StringProperty(
        name="Output",
        description="Multi-layer EXR file for the render passes (// is relative to the .blend)",
        subtype="FILE_PATH",
        default="//bounce_gi.exr",
    )

    def method_id(self) -> str:
        """The method as the engine's RenderSettings spells it ("none" | "lpv" | "vct")."""
        return self.method.lower()


classes = (BounceGISettings,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.bounce_gi = bpy.props.PointerProperty(type=BounceGISettings)


def unregister():
    # The property must go before its class: Blender keeps a reference to the type.
    del bpy.types.Scene.bounce_gi
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
