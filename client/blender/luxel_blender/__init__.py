"""Luxel lightmap baker for Blender: exports the scene with Blender's glTF
exporter, bakes it on a luxeld daemon (or in-process) through the `luxel`
CLI, streams the progressive lightmap into an image and applies the result
(lightmap UVs, image, material wiring). See docs/blender.md."""

bl_info = {
    "name": "Luxel Lightmap Baker",
    "author": "Luxel",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "Properties > Render > Luxel Lightmap",
    "description": "Bake lightmaps with Luxel (luxeld or local) and apply them",
    "category": "Render",
}

import bpy
from bpy.props import PointerProperty

from . import operators, preferences, properties, session, ui

_classes = (preferences.LuxelPreferences, properties.LuxelSceneSettings,
            *operators.classes, *ui.classes)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.luxel = PointerProperty(type=properties.LuxelSceneSettings)
    bpy.types.STATUSBAR_HT_header.append(ui.draw_status)


def unregister():
    running = session.active()
    if running is not None:
        running.cancel()  # nobody would apply it once the add-on is gone
    bpy.types.STATUSBAR_HT_header.remove(ui.draw_status)
    del bpy.types.Scene.luxel
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
