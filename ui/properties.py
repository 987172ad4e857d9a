# SPDX-License-Identifier: GPL-3.0-or-later
"""Per-scene settings, stored in the .blend as `bpy.types.Scene.bounce_gi`.

Only user choices live here. Results of the last render are runtime state (see preview.py)
so that a preview never dirties or bloats the file.
"""
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty
from bpy.types import PropertyGroup

# Identifiers are upper case (Blender convention); the engine wants lower case (method_id()).
METHOD_ITEMS = (
    ("AUTO", "Auto", "The fastest measured setting (addon/quality_front.json) that reaches the chosen quality's "
                     "error against Cycles"),
    ("NONE", "Direct only", "Direct light with shadow maps, no indirect bounce"),
    ("LPV", "Light Propagation Volumes", "Indirect light propagated through a grid of SH coefficients"),
    ("VCT", "Voxel Cone Tracing", "Indirect light gathered by tracing cones through a voxel mip chain"),
)

# Blender 4.5+ warns when a path property without this flag is given a "//" (relative to the .blend) path; older
# versions do not know the flag. ANIMATABLE is the default the options replace.
PATH_OPTIONS = {"ANIMATABLE", "PATH_SUPPORTS_BLEND_RELATIVE"} if bpy.app.version >= (4, 5, 0) else {"ANIMATABLE"}


def redraw_views(_self, _context) -> None:
    """A display change needs no GI update, only a redraw of every 3D view."""
    from .preview import tag_redraw_all

    tag_redraw_all(("VIEW_3D",))


class BounceGISettings(PropertyGroup):
    """What the Render Preview operator renders, and where it writes the render passes."""

    method: EnumProperty(
        name="Method",
        description="How indirect (bounced) light is computed",
        items=METHOD_ITEMS,
        # Auto: a setting measured to be fast for its error, rather than one method's most expensive defaults (a
        # furnished room took minutes at VCT's defaults on a software GL).
        default="AUTO",
    )
    quality: EnumProperty(
        name="Quality",
        description="With Auto: the error to reach; with a method: its settings (Medium: the method's defaults)",
        items=[("DRAFT", "Draft", "Fast: coarser grids, fewer cones"), ("MEDIUM", "Medium", "The defaults"),
               ("HIGH", "High", "More accurate, slower")],
        default="MEDIUM",
    )
    bounces: IntProperty(
        name="Bounces",
        description="Indirect bounces (LPV and VCT; 0: the quality's, 8 like Cycles' default)",
        min=0, max=8, default=0,
    )
    grid_resolution: IntProperty(
        name="Grid",
        description="Grid cells along the scene's longest axis (LPV 4..256, VCT 16..512; 0: the quality's)",
        min=0, max=512, default=0,
    )
    use_time_budget: BoolProperty(
        name="Time Budget",
        description="Choose method and settings automatically: the most accurate measured (addon/quality_front.json, "
                    "written by `bounce-gi bench`) that fits the frame time below",
        default=False,
    )
    time_budget_ms: FloatProperty(
        name="Budget (ms)",
        description="Frame time the automatic choice may spend, in milliseconds (times measured on the machine "
                    "named in the quality table)",
        min=1.0,
        soft_max=10000.0,
        default=1000.0,
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
        description="Multi-layer EXR file the Render Preview also writes its render passes to (// is relative to "
                    "the .blend); leave empty to only show the preview image",
        subtype="FILE_PATH",
        options=PATH_OPTIONS,
        default="",
    )

    compare_samples: IntProperty(
        name="Cycles Samples",
        description="Samples per pixel of each of the two seeds of the Cycles reference that Compare with Cycles "
                    "renders (at the preview resolution; cached, so a second comparison of the same scene is "
                    "instant)",
        min=1,
        soft_max=4096,
        default=64,
    )

    display_mode: EnumProperty(
        name="Display",
        description="What Rendered shading and the overlay draw",
        items=[("COMBINED", "Combined", "Direct and indirect light, times the surface colour, plus emission"),
               ("INDIRECT", "Indirect Only", "Only the bounced light (Diffuse Indirect × colour)"),
               ("DIRECT", "Direct Only", "Only the direct light and emission")],
        default="COMBINED",
        update=redraw_views,
    )

    def method_id(self) -> str:
        """The method as the engine's RenderSettings spells it ("auto" | "none" | "lpv" | "vct"; "auto" is resolved
        by preview.render_settings_of, never sent to the engine)."""
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
