# Writes a .glb with one plane whose material Blender's glTF exporter turns
# into KHR_materials_unlit (a Background shader straight into the material
# output is its "shadeless" form). Run by blender_unlit_test with Blender
# 5.0.1's bpy module: python blender_unlit_export.py -- OUT.glb
import sys

import bpy

out = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_plane_add(size=2)
plane = bpy.context.active_object
mat = bpy.data.materials.new("unlit_floor")
mat.use_nodes = True
nodes = mat.node_tree.nodes
for n in list(nodes):
    nodes.remove(n)
output = nodes.new("ShaderNodeOutputMaterial")
background = nodes.new("ShaderNodeBackground")
background.inputs["Color"].default_value = (0.8, 0.55, 0.3, 1.0)
mat.node_tree.links.new(background.outputs["Background"], output.inputs["Surface"])
plane.data.materials.append(mat)
bpy.ops.export_scene.gltf(filepath=out, export_format="GLB")
