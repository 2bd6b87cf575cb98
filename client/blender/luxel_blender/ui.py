"""The Luxel panel (Render properties) and the status bar entry."""

import bpy

from . import preferences
from . import session as sessions


class LUXEL_PT_bake(bpy.types.Panel):
    bl_label = "Luxel Lightmap"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        layout = self.layout
        s = context.scene.luxel
        prefs = preferences.get(context)
        if prefs is not None:
            layout.label(text=(f"luxeld at {prefs.server}" if prefs.mode == "SERVER"
                               else "in-process (luxel bake --local)"), icon="WORLD")
        col = layout.column()
        for name in ("resolution", "samples", "bounces", "time_s", "snapshot_interval_s",
                     "selection_only", "baked_only", "extra_args"):
            col.prop(s, name)
        running = sessions.active()
        if running is None:
            layout.operator("luxel.bake", icon="RENDER_STILL")
        else:
            layout.label(text=running.status_text())
            layout.operator("luxel.cancel", icon="CANCEL")
        row = layout.row()
        row.operator("luxel.apply_results", icon="IMPORT")
        row.operator("luxel.restore_meshes", icon="LOOP_BACK")


def draw_status(self, context):
    running = sessions.active()
    if running is not None:
        self.layout.label(text=running.status_text(), icon="LIGHT")


classes = (LUXEL_PT_bake,)
