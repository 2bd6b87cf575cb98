"""Where luxel is and which daemon to use: the add-on's preferences."""

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty


class LuxelPreferences(bpy.types.AddonPreferences):
    # The add-on's module: "luxel_blender" as a legacy add-on,
    # "bl_ext.<repo>.luxel_blender" as an extension.
    bl_idname = __package__

    luxel_path: StringProperty(
        name="luxel binary", subtype="FILE_PATH", default="luxel",
        description="The luxel command line tool (e.g. <build>/client/luxel); the add-on drives "
                    "it for bakes on a daemon and in-process")
    mode: EnumProperty(
        name="Bake on", default="SERVER",
        items=[("SERVER", "luxeld", "Upload to a luxeld daemon and watch the bake"),
               ("LOCAL", "This machine", "Run `luxel bake --local` (no progressive snapshots)")])
    server: StringProperty(name="Daemon address", default="127.0.0.1:50051",
                           description="HOST:PORT of luxeld")
    token_file: StringProperty(
        name="Token file", subtype="FILE_PATH", default="",
        description="File holding the daemon's bearer token (empty: no authentication)")
    work_dir: StringProperty(
        name="Work folder", subtype="DIR_PATH", default="",
        description="Exported scenes, snapshots and results go here (empty: a luxel folder "
                    "beside the .blend file, or the system's temporary folder)")

    def draw(self, context):
        col = self.layout.column()
        col.prop(self, "luxel_path")
        col.prop(self, "mode")
        sub = col.column()
        sub.active = self.mode == "SERVER"
        sub.prop(self, "server")
        sub.prop(self, "token_file")
        col.prop(self, "work_dir")


def get(context=None):
    """The preferences, or defaults when the module was loaded without being
    enabled as an add-on (scripts that import it directly)."""
    context = context or bpy.context
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon is not None else None
