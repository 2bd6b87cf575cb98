"""One scene exported twice by Blender's glTF exporter: plain and with
KHR_draco_mesh_compression (Blender's Draco encoder at its default
quantisation: positions 14 bits, normals 10, texture coordinates 12).

Usage: python (with bpy) blender_compressed_export.py -- OUT_DIR
Writes OUT_DIR/plain.glb and OUT_DIR/draco.glb. The scene: a 4 x 4 floor,
a cube standing on it and a smooth UV sphere (flat and smooth normals,
shared and split vertices). Every mesh has two UV maps, so the files carry
TEXCOORD_0 and TEXCOORD_1 (lightmap UVs: a copy of the default unwrap, which
does not overlap itself).
"""
import os
import sys

import bpy


def main():
    out_dir = sys.argv[sys.argv.index("--") + 1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0, 0, 0))
    bpy.context.object.name = "floor"
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-0.8, 0.3, 0.5))
    bpy.context.object.name = "cube"
    bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12, radius=0.6,
                                         location=(0.9, -0.2, 0.6))
    bpy.context.object.name = "sphere"
    bpy.ops.object.shade_smooth()
    for obj in bpy.data.objects:
        mat = bpy.data.materials.new(obj.name + "_grey")
        mat.use_nodes = True
        mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (
            0.6, 0.6, 0.6, 1.0)
        mat.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 1.0
        obj.data.materials.append(mat)
        obj.data.uv_layers.new(name="lightmap", do_init=True)
    common = dict(export_format="GLB", use_selection=False, export_apply=True,
                  export_texcoords=True, export_normals=True, export_materials="EXPORT",
                  export_cameras=False, export_lights=False)
    bpy.ops.export_scene.gltf(filepath=os.path.join(out_dir, "plain.glb"), **common)
    bpy.ops.export_scene.gltf(filepath=os.path.join(out_dir, "draco.glb"),
                              export_draco_mesh_compression_enable=True, **common)


main()
