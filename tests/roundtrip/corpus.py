"""Source scenes for the write-back round trip (roundtrip_test.py).

Each case is a glTF file of a kind the public sample sets have, made by an
independent writer where one is available here: Blender's own glTF exporter
(bpy 5.0.1) for what Blender can author (meshes without UVs, two UV maps with
a texture on the second, vertex colours, skins, shape keys, several
materials, linked duplicates, Draco), and hand-written JSON for what it
cannot (strips and fans, a material reading a set the primitive lacks,
KHR_texture_transform's texCoord override, sparse accessors).
"""
import base64
import json
import math
import os
import struct
import zlib

import bpy


def _reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def _export(path, **options):
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLB", export_yup=True,
                              export_apply=False, **options)


def _cube(name, location=(0, 0, 0), size=1.0):
    bpy.ops.mesh.primitive_cube_add(size=size, location=location)
    obj = bpy.context.active_object
    obj.name = name
    obj.data.name = name
    return obj


def _floor(size=6.0):
    bpy.ops.mesh.primitive_plane_add(size=size, location=(0, 0, -0.5))
    obj = bpy.context.active_object
    obj.name = obj.data.name = "floor"
    return obj


def _drop_uvs(obj):
    while obj.data.uv_layers:
        obj.data.uv_layers.remove(obj.data.uv_layers[0])


def _material(name, color=(0.8, 0.8, 0.8, 1.0)):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = color
    return mat


def _checker_image(name):
    img = bpy.data.images.new(name, 4, 4)
    px = []
    for y in range(4):
        for x in range(4):
            on = (x + y) % 2
            px += [on, 0.2, 1 - on, 1.0]
    img.pixels = px
    img.pack()
    return img


def box_no_uv(path):
    """Khronos' Box: a mesh with no TEXCOORD at all."""
    _reset()
    for obj in (_cube("box"), _floor()):
        _drop_uvs(obj)
        obj.data.materials.append(_material("grey"))
    _export(path)


def two_uv_sets(path):
    """Khronos' MultiUVTest: two UV maps, an emissive texture read through the second."""
    _reset()
    obj = _cube("logo_cube")
    second = obj.data.uv_layers.new(name="logo_uv")
    for i, loop_uv in enumerate(second.data):  # a different layout from the first
        u, v = obj.data.uv_layers[0].data[i].uv
        loop_uv.uv = (v, 1 - u)
    mat = _material("logo")
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = _checker_image("logo")
    uvmap = nodes.new("ShaderNodeUVMap")
    uvmap.uv_map = "logo_uv"
    links.new(uvmap.outputs["UV"], tex.inputs["Vector"])
    bsdf = nodes["Principled BSDF"]
    links.new(tex.outputs["Color"], bsdf.inputs["Emission Color"])
    bsdf.inputs["Emission Strength"].default_value = 1.0
    obj.data.materials.append(mat)
    _floor().data.materials.append(_material("grey"))
    _export(path)


def vertex_colors(path):
    """Khronos' BoxVertexColors: COLOR_0 and no UVs."""
    _reset()
    obj = _cube("painted")
    _drop_uvs(obj)
    attr = obj.data.color_attributes.new("Col", "FLOAT_COLOR", "CORNER")
    for i, c in enumerate(attr.data):
        c.color = ((i % 3) / 2, (i % 5) / 4, 0.5, 1.0)
    obj.data.materials.append(_material("painted"))
    _export(path, export_vertex_color="ACTIVE")


def skinned(path):
    """Khronos' SimpleSkin: a skinned cylinder (JOINTS_0, WEIGHTS_0), no UVs."""
    _reset()
    bpy.ops.mesh.primitive_cylinder_add(vertices=12, depth=2, location=(0, 0, 1))
    body = bpy.context.active_object
    body.name = body.data.name = "skinned"
    _drop_uvs(body)
    bpy.ops.object.armature_add(location=(0, 0, 0))
    rig = bpy.context.active_object
    body.parent = rig
    mod = body.modifiers.new("Armature", "ARMATURE")
    mod.object = rig
    group = body.vertex_groups.new(name=rig.data.bones[0].name)
    group.add([v.index for v in body.data.vertices], 1.0, "REPLACE")
    body.data.materials.append(_material("skin"))
    _export(path, export_skins=True)


def morph(path):
    """Khronos' AnimatedMorphCube: shape keys (morph targets), one UV map."""
    _reset()
    obj = _cube("morph_cube")
    obj.shape_key_add(name="Basis")
    key = obj.shape_key_add(name="Thin")
    for i, p in enumerate(key.data):
        p.co.x *= 0.5
    obj.data.materials.append(_material("morph"))
    _export(path, export_morph=True)


def multi_material(path):
    """Several primitives per mesh (one per material), one UV map."""
    _reset()
    obj = _cube("two_materials")
    obj.data.materials.append(_material("red", (0.8, 0.1, 0.1, 1)))
    obj.data.materials.append(_material("blue", (0.1, 0.1, 0.8, 1)))
    for poly in obj.data.polygons:
        poly.material_index = poly.index % 2
    _export(path)


def linked_duplicates(path):
    """One mesh on several nodes at different scales, no UVs."""
    _reset()
    first = _cube("shared")
    _drop_uvs(first)
    first.data.materials.append(_material("grey"))
    for i in range(1, 3):
        dup = first.copy()
        dup.location = (2.0 * i, 0, 0)
        dup.scale = (0.5 * i, 0.5 * i, 0.5 * i)
        bpy.context.scene.collection.objects.link(dup)
    _export(path)


def draco(path):
    """KHR_draco_mesh_compression from Blender's exporter (its Draco encoder)."""
    _reset()
    _cube("draco_cube").data.materials.append(_material("grey"))
    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8, location=(2, 0, 0))
    sphere = bpy.context.active_object
    sphere.name = sphere.data.name = "draco_sphere"
    _floor()
    _export(path, export_draco_mesh_compression_enable=True)


# Hand-written JSON --------------------------------------------------------


class _Builder:
    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}],
                    "nodes": [], "meshes": [], "materials": [], "accessors": [],
                    "bufferViews": []}

    def view(self, data):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.bin),
                                        "byteLength": len(data)})
        self.bin += data
        return len(self.doc["bufferViews"]) - 1

    def floats(self, values, kind):
        n = {"VEC2": 2, "VEC3": 3}[kind]
        acc = {"bufferView": self.view(struct.pack(f"<{len(values)}f", *values)),
               "componentType": 5126, "count": len(values) // n, "type": kind}
        if kind == "VEC3":
            acc["min"] = [min(values[i::3]) for i in range(3)]
            acc["max"] = [max(values[i::3]) for i in range(3)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def indices(self, values):
        self.doc["accessors"].append({"bufferView": self.view(struct.pack(f"<{len(values)}H", *values)),
                                      "componentType": 5123, "count": len(values), "type": "SCALAR"})
        return len(self.doc["accessors"]) - 1

    def node(self, name, primitives, translation=(0, 0, 0)):
        self.doc["meshes"].append({"name": name, "primitives": primitives})
        self.doc["nodes"].append({"name": name, "mesh": len(self.doc["meshes"]) - 1,
                                  "translation": list(translation)})
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)

    def texture(self):
        self.doc.setdefault("images", []).append({"bufferView": self.view(_png_2x2()),
                                                  "mimeType": "image/png"})
        self.doc.setdefault("textures", []).append({"source": len(self.doc["images"]) - 1})
        return len(self.doc["textures"]) - 1

    def write(self, path):
        self.doc["buffers"] = [{"byteLength": len(self.bin),
                                "uri": "data:application/octet-stream;base64,"
                                       + base64.b64encode(bytes(self.bin)).decode()}]
        with open(path, "w") as f:
            json.dump(self.doc, f)


def _png_2x2():
    """A 2x2 RGBA PNG (PNG specification: IHDR, one IDAT of zlib data, IEND)."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    rows = b"".join(b"\0" + bytes(px) for px in ([255, 0, 0, 255, 0, 255, 0, 255],
                                                  [0, 0, 255, 255, 255, 255, 255, 255]))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 2, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def _grid(nx, ny, z=0.0, size=2.0):
    """A wavy nx x ny vertex grid: positions, normals, TEXCOORD-like uvs."""
    pos, nrm, uv = [], [], []
    for j in range(ny):
        for i in range(nx):
            x, y = size * i / (nx - 1) - size / 2, size * j / (ny - 1) - size / 2
            pos += [x, z + 0.1 * math.sin(3 * x), y]
            nrm += [0, 1, 0]
            uv += [i / (nx - 1), j / (ny - 1)]
    return pos, nrm, uv


def strips_and_fans(path):
    """Triangle strips and fans (glTF modes 5 and 6), no UVs."""
    b = _Builder()
    b.doc["materials"].append({"name": "grey"})
    pos, nrm, _ = _grid(6, 2)
    strip = [k for i in range(6) for k in (i, 6 + i)]
    b.node("strip", [{"attributes": {"POSITION": b.floats(pos, "VEC3"),
                                     "NORMAL": b.floats(nrm, "VEC3")},
                      "indices": b.indices(strip), "mode": 5, "material": 0}])
    fan = [0, 0.3, 0]
    for k in range(9):
        a = 2 * math.pi * k / 8
        fan += [math.cos(a), 0, math.sin(a)]
    b.node("fan", [{"attributes": {"POSITION": b.floats(fan, "VEC3")}, "mode": 6, "material": 0}],
           translation=(0, 0, 3))
    b.write(path)


def texcoord_read_but_absent(path):
    """A material reading texCoord 1 on a primitive with only TEXCOORD_0."""
    b = _Builder()
    tex = b.texture()
    b.doc["materials"].append({"name": "occluded",
                               "occlusionTexture": {"index": tex, "texCoord": 1},
                               "pbrMetallicRoughness": {"baseColorTexture": {"index": tex}}})
    pos, nrm, uv = _grid(5, 5)
    idx = [k for j in range(4) for i in range(4)
           for k in (j * 5 + i, (j + 1) * 5 + i, j * 5 + i + 1,
                     j * 5 + i + 1, (j + 1) * 5 + i, (j + 1) * 5 + i + 1)]
    b.node("sheet", [{"attributes": {"POSITION": b.floats(pos, "VEC3"), "NORMAL": b.floats(nrm, "VEC3"),
                                     "TEXCOORD_0": b.floats(uv, "VEC2")},
                      "indices": b.indices(idx), "material": 0}])
    b.write(path)


def texture_transform_override(path):
    """KHR_texture_transform overriding texCoord to 1 with TEXCOORD_0 and _1 present."""
    b = _Builder()
    tex = b.texture()
    b.doc["extensionsUsed"] = ["KHR_texture_transform"]
    b.doc["materials"].append({"name": "transformed", "pbrMetallicRoughness": {"baseColorTexture": {
        "index": tex, "extensions": {"KHR_texture_transform": {"scale": [2, 2], "texCoord": 1}}}}})
    pos, nrm, uv = _grid(5, 5)
    uv1 = [c * 0.5 for c in uv]
    # Overlapping second set (every quad the same square): --uv auto regenerates.
    idx = [k for j in range(4) for i in range(4)
           for k in (j * 5 + i, (j + 1) * 5 + i, j * 5 + i + 1,
                     j * 5 + i + 1, (j + 1) * 5 + i, (j + 1) * 5 + i + 1)]
    b.node("tiles", [{"attributes": {"POSITION": b.floats(pos, "VEC3"), "NORMAL": b.floats(nrm, "VEC3"),
                                     "TEXCOORD_0": b.floats(uv, "VEC2"),
                                     "TEXCOORD_1": b.floats(uv1, "VEC2")},
                      "indices": b.indices(idx), "material": 0}])
    b.write(path)


def sparse_positions(path):
    """A POSITION accessor with sparse substitution (glTF 2.0 §3.6.2.3), TEXCOORD_0."""
    b = _Builder()
    b.doc["materials"].append({"name": "grey"})
    pos, nrm, uv = _grid(4, 4)
    acc = b.floats(pos, "VEC3")
    lifted = [5, 6]
    values = []
    for v in lifted:
        values += [pos[3 * v], pos[3 * v + 1] + 0.4, pos[3 * v + 2]]
    b.doc["accessors"][acc]["sparse"] = {
        "count": len(lifted),
        "indices": {"bufferView": b.view(struct.pack("<2H", *lifted)), "componentType": 5123},
        "values": {"bufferView": b.view(struct.pack(f"<{len(values)}f", *values))}}
    b.doc["accessors"][acc]["max"][1] += 0.4
    idx = [k for j in range(3) for i in range(3)
           for k in (j * 4 + i, (j + 1) * 4 + i, j * 4 + i + 1,
                     j * 4 + i + 1, (j + 1) * 4 + i, (j + 1) * 4 + i + 1)]
    b.node("sparse", [{"attributes": {"POSITION": acc, "NORMAL": b.floats(nrm, "VEC3"),
                                      "TEXCOORD_0": b.floats(uv, "VEC2")},
                       "indices": b.indices(idx), "material": 0}])
    b.write(path)


CASES = {
    "box_no_uv.glb": box_no_uv,
    "two_uv_sets.glb": two_uv_sets,
    "vertex_colors.glb": vertex_colors,
    "skinned.glb": skinned,
    "morph.glb": morph,
    "multi_material.glb": multi_material,
    "linked_duplicates.glb": linked_duplicates,
    "draco.glb": draco,
    "strips_and_fans.gltf": strips_and_fans,
    "texcoord_read_but_absent.gltf": texcoord_read_but_absent,
    "texture_transform_override.gltf": texture_transform_override,
    "sparse_positions.gltf": sparse_positions,
}


def make(folder):
    """Writes every case into `folder`; returns their paths."""
    os.makedirs(folder, exist_ok=True)
    paths = []
    for name, make_case in CASES.items():
        path = os.path.join(folder, name)
        make_case(path)
        paths.append(path)
    return paths
