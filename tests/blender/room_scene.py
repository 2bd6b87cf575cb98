"""A small closed room built with bpy for the add-on tests: floor, ceiling,
four walls (red left, green right), a box and an emissive ceiling panel. Its
light comes only from the panel, so the bake does not depend on the sky."""

import math

import bpy

ALBEDO = {
    "Floor": (0.7, 0.7, 0.7),
    "Ceiling": (0.7, 0.7, 0.7),
    "WallBack": (0.7, 0.7, 0.7),
    "WallFront": (0.7, 0.7, 0.7),
    "WallLeft": (0.7, 0.15, 0.15),
    "WallRight": (0.15, 0.7, 0.15),
    "Box": (0.6, 0.6, 0.5),
    "Panel": (0.8, 0.8, 0.8),
}
PANEL_EMISSION = 20.0  # emission strength of the panel's white material


def _material(name, albedo, emission=0.0):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:
        mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*albedo, 1.0)
    bsdf.inputs["Roughness"].default_value = 1.0
    if emission:
        bsdf.inputs["Emission Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission
    return mat


def _plane(name, size, location, rotation):
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=location, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    obj.scale = (*size, 1.0)
    return obj


def clear():
    """Removes every object and the data it used. Not read_factory_settings:
    that would reset the preferences, and with them the enabled add-on."""
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.images,
                       bpy.data.cameras, bpy.data.lights):
        for item in list(collection):
            collection.remove(item)


def build_room():
    """Empties the file and builds the room (4 x 4 x 3 m, floor at z = 0)."""
    clear()
    half, height = 2.0, 3.0
    quarter = math.pi / 2
    objects = [
        _plane("Floor", (4, 4), (0, 0, 0), (0, 0, 0)),
        _plane("Ceiling", (4, 4), (0, 0, height), (math.pi, 0, 0)),
        _plane("WallBack", (4, height), (0, half, height / 2), (quarter, 0, 0)),
        _plane("WallFront", (4, height), (0, -half, height / 2), (-quarter, 0, 0)),
        _plane("WallLeft", (height, 4), (-half, 0, height / 2), (0, quarter, 0)),
        _plane("WallRight", (height, 4), (half, 0, height / 2), (0, -quarter, 0)),
        _plane("Panel", (1, 1), (0, 0, height - 0.01), (math.pi, 0, 0)),
    ]
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.5, 0.3, 0.5), rotation=(0, 0, 0.4))
    box = bpy.context.active_object
    box.name = box.data.name = "Box"
    objects.append(box)
    for obj in objects:
        emission = PANEL_EMISSION if obj.name == "Panel" else 0.0
        obj.data.materials.append(_material(obj.name, ALBEDO[obj.name], emission))
    # Planes face +z before rotation; the transforms above turn every one
    # towards the inside of the room. Apply them so the exported meshes carry
    # world coordinates and the test's expectations do not depend on them.
    bpy.ops.object.select_all(action="SELECT")
    bpy.ops.object.transform_apply(location=False, rotation=True, scale=True)
    bpy.ops.object.select_all(action="DESELECT")
    cam_data = bpy.data.cameras.new("Camera")
    cam = bpy.data.objects.new("Camera", cam_data)
    bpy.context.scene.collection.objects.link(cam)
    cam.location = (0.0, -1.95, 1.5)
    cam.rotation_euler = (math.radians(90), 0, 0)
    cam_data.lens = 14
    bpy.context.scene.camera = cam
    return objects
