# SPDX-License-Identifier: GPL-3.0-or-later
"""Sidebar panels in the 3D View (N panel, tab "Bounce GI"): settings, render button, last result; and the
Render Properties panel shown while Bounce GI is the render engine (same settings, same draw function).

Panels only read state; everything they show about the last render comes from
`preview.state`, which lives in memory and is never written into the .blend.
"""
import bpy
from bpy.types import Panel

from . import preview


def _format_seconds(seconds: float) -> str:
    # Passes range from microseconds to seconds on a software rasteriser; ms reads best.
    return f"{seconds * 1000:.1f} ms" if seconds < 10 else f"{seconds:.1f} s"


def draw_render_settings(layout, settings) -> None:
    """The settings F12 and the preview share: time budget and method (what render_settings_of() reads). Both the
    sidebar and the Render Properties panel draw them with this."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    layout.prop(settings, "use_time_budget")
    if settings.use_time_budget:
        layout.prop(settings, "time_budget_ms")
    row = layout.row()
    row.enabled = not settings.use_time_budget  # the budget picks the method
    row.prop(settings, "method")


class VIEW3D_PT_bounce_gi(Panel):
    """Bounce GI settings and the Render Preview button."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Bounce GI"
    bl_label = "Bounce GI"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.bounce_gi
        draw_render_settings(layout, settings)
        layout.prop(settings, "resolution_percentage")
        layout.prop(settings, "output_path")

        row = layout.row()
        row.scale_y = 1.4
        if preview.state.busy:
            # The operator's poll() greys the button out; say why right here as well.
            row.enabled = False
            row.operator("bounce_gi.render_preview", text="Rendering...", icon="TIME")
        else:
            row.operator("bounce_gi.render_preview", icon="RENDER_STILL")
        if preview.state.last_error:
            layout.label(text=preview.state.last_error, icon="ERROR")


class VIEW3D_PT_bounce_gi_last_render(Panel):
    """Per-pass times and warnings of the last finished preview."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Bounce GI"
    bl_label = "Last Render"
    bl_parent_id = "VIEW3D_PT_bounce_gi"

    @classmethod
    def poll(cls, context):
        return preview.state.last is not None

    def draw(self, context):
        layout = self.layout
        last = preview.state.last
        layout.label(text=f"{last.method.upper()}  {last.width} x {last.height}", icon="IMAGE_DATA")
        if last.quality:
            layout.label(text=last.quality, icon="AUTO")
        if last.output:
            layout.label(text=f"Passes: {bpy.path.basename(last.output)}", icon="FILE_IMAGE")

        col = layout.column(align=True)
        # Engine order is pipeline order; "total" goes last, then the wall time the user waited.
        for name, seconds in last.timings.items():
            if name != "total":
                split = col.split(factor=0.6)
                split.label(text=name)
                # A pass whose inputs did not change is reused, not re-run: say so instead of "0.0 ms".
                split.label(text="cached" if name in last.skipped else _format_seconds(seconds))
        if "total" in last.timings:
            split = col.split(factor=0.6)
            split.label(text="Total (engine)")
            split.label(text=_format_seconds(last.timings["total"]))
        split = col.split(factor=0.6)
        split.label(text="Waited")
        split.label(text=_format_seconds(last.wall_seconds))

        if last.warnings:
            box = layout.box()
            box_col = box.column(align=True)
            for text in last.warnings:
                box_col.label(text=text, icon="ERROR")


class RENDER_PT_bounce_gi(Panel):
    """Render Properties with the Bounce GI engine: what F12 and `blender -b -E BOUNCE_GI` render with. The render
    size is the scene's (Format panel), so the preview's resolution and Output settings are not shown here."""

    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_label = "Bounce GI"
    COMPAT_ENGINES = {"BOUNCE_GI"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        draw_render_settings(self.layout, context.scene.bounce_gi)


classes = (VIEW3D_PT_bounce_gi, VIEW3D_PT_bounce_gi_last_render, RENDER_PT_bounce_gi)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
