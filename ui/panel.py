# SPDX-License-Identifier: GPL-3.0-or-later
"""Sidebar panels in the 3D View (N panel, tab "Bounce GI"): settings, render button, last result; and the
Render Properties panel shown while Bounce GI is the render engine (same settings, same draw function).

Panels only read state; everything they show about the last render comes from
`preview.state` (the last comparison with Cycles: `compare.state`), which lives in memory and is never
written into the .blend.
"""
import bpy
from bpy.types import Panel

from . import compare, overlay, preview, viewport


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
    col = layout.column()
    col.enabled = not settings.use_time_budget  # the budget picks method and settings
    col.prop(settings, "method")
    col.prop(settings, "quality")
    if settings.method in ("LPV", "VCT"):  # advanced: overrides of the quality's settings
        col.prop(settings, "bounces")
        col.prop(settings, "grid_resolution")


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
        row = layout.row(align=True)
        row.operator("bounce_gi.toggle_overlay", text="GI Overlay", icon="OVERLAY", depress=overlay.is_on())
        row.prop(settings, "display_mode", text="")
        layout.operator("bounce_gi.bake_color_attribute", icon="GROUP_VCOL")


class VIEW3D_PT_bounce_gi_viewport(Panel):
    """The live viewport GI (Rendered shading or the overlay): the stage on screen, latency, cost, atlas."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Bounce GI"
    bl_label = "Viewport GI"
    bl_parent_id = "VIEW3D_PT_bounce_gi"

    @classmethod
    def poll(cls, context):
        return viewport.newest_feed() is not None

    def draw(self, context):
        feed = viewport.newest_feed()
        s = feed.session.stats
        layout = self.layout
        layout.label(text=feed.status().removeprefix("Bounce GI: "), icon="ERROR" if s.error else "SHADING_RENDERED")
        if s.changed:
            layout.label(text=f"Last edit: {s.changed}")
        col = layout.column(align=True)
        rows = [(f"Edit → {stage}", seconds) for stage, seconds in s.latency.items()]
        rows += [(f"Main thread: {part}", seconds) for part, seconds in s.main_thread.items()]
        rows += [(name, seconds) for name, seconds in s.timings.items()]
        for name, seconds in rows:
            split = col.split(factor=0.6)
            split.label(text=name)
            split.label(text="cached" if name in s.skipped else _format_seconds(seconds))
        if s.texels:
            layout.label(text=f"{s.triangles} triangles, {s.texels} texels of {s.texel_size * 100:.1f} cm")
            lights = ", ".join(f"{n} {kind.lower()}" for kind, n in s.lights.items()) or "none"
            layout.label(text=f"Lights: {lights}")
        if s.grid:
            layout.label(text=f"Grid: {s.grid}")
        for text in s.skipped_work:
            layout.label(text=f"Skipped {text}", icon="FORWARD")
        for text in s.warnings:
            layout.label(text=text, icon="ERROR")


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


class VIEW3D_PT_bounce_gi_compare(Panel):
    """Compare with Cycles: samples, the button, and rel-L1 per pass of the last comparison."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Bounce GI"
    bl_label = "Compare with Cycles"
    bl_parent_id = "VIEW3D_PT_bounce_gi"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(context.scene.bounce_gi, "compare_samples")
        state = compare.state
        row = layout.row()
        if state.busy:
            row.enabled = False
            row.operator("bounce_gi.compare_cycles", text="Comparing...", icon="TIME")
            if state.status:
                layout.label(text=state.status)
        else:
            row.operator("bounce_gi.compare_cycles", icon="IMAGE_REFERENCE")
        if state.last_error:
            layout.label(text=state.last_error, icon="ERROR")
        if state.last is not None:
            draw_compare_report(layout, state.last)


def draw_compare_report(layout, report: dict) -> None:
    """rel-L1 per pass beside Cycles' own noise, relMSE, times and the images to look at."""
    ref = report["reference"]
    layout.label(text=f"{report['method'].upper()} {report['resolution'][0]} x {report['resolution'][1]} vs "
                      f"Cycles {ref['samples']} spp x 2", icon="IMAGE_DATA")
    col = layout.column(align=True)
    split = col.split(factor=0.5)
    split.label(text="Pass")
    split.split(factor=0.5).label(text="rel-L1")
    split.label(text="noise")
    for key, label in compare.PASS_LABELS.items():
        if key not in report["rel_l1"]:
            continue  # Cycles left the pass black (e.g. no glossy surface in view)
        split = col.split(factor=0.5)
        split.label(text=label)
        row = split.split(factor=0.5)
        row.label(text=f"{report['rel_l1'][key]:.3f}")
        row.label(text=f"{report['noise_floor'][key]:.3f}")
    col.label(text=f"relMSE {report['rel_mse']:.4f}; Diffuse Color match {report['diffuse_color_match']:.1%}")
    s = report["seconds"]
    col.label(text=f"Ours {_format_seconds(s['ours'])}; Cycles {_format_seconds(s['cycles'])}"
                   + (" (cached)" if s["cycles_cached"] else ""))
    col.label(text="Images: " + ", ".join(name.removeprefix("Bounce GI Compare: ") for name in compare.IMAGES.values()))
    for text in report["warnings"]:
        layout.label(text=text, icon="ERROR")


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
        self.layout.prop(context.scene.bounce_gi, "display_mode")


classes = (VIEW3D_PT_bounce_gi, VIEW3D_PT_bounce_gi_viewport, VIEW3D_PT_bounce_gi_last_render,
           VIEW3D_PT_bounce_gi_compare, RENDER_PT_bounce_gi)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
