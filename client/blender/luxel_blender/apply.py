"""Puts a finished bake into the scene: the lightmap image, the lightmap UVs
on the user's objects, and materials that show lightmap x base colour.

The UVs: Luxel generates lightmap UVs on the geometry it was sent, cutting
charts along triangle edges and duplicating vertices on chart seams, and
writes that geometry back as <scene>_lightmapped.glb. A Blender mesh has
quads and n-gons and shares vertices across those seams, so the generated
UVs cannot be copied onto it corner for corner in general (a quad whose two
triangles fall into different charts has no valid per-corner UVs). The add-on
therefore swaps each baked object's mesh for the geometry Luxel baked, read
from the write-back: same object, transform, modifiers and materials, the
user's UV maps kept under their names, plus a "LuxelLightmap" layer in atlas
space. The previous mesh is kept (fake user, named in the object's
"luxel_original_mesh" property) so nothing the user made is lost."""

import contextlib
import json
import math
import os
import re

import bpy
import numpy as np

from . import glb as glb_reader

LIGHTMAP_IMAGE = "Luxel Lightmap"
LIGHTMAP_UV = "LuxelLightmap"
ORIGINAL_MESH_PROP = "luxel_original_mesh"
_NODE_PREFIX = "Luxel "


def lightmap_image(path, name=LIGHTMAP_IMAGE):
    """The one lightmap image, (re)pointed at ``path`` and reloaded, so a
    material or Image Editor showing it follows the bake as it refines."""
    image = bpy.data.images.get(name)
    if image is None:
        image = bpy.data.images.load(path, check_existing=False)
        image.name = name
    else:
        image.filepath = path
        image.reload()
    # Irradiance in W/m^2, linear: no view transform may touch it.
    image.colorspace_settings.is_data = True
    image.update_tag()
    return image


def _manifest_texcoord(results_dir):
    """The lightmap TEXCOORD index the manifest names, or None."""
    try:
        with open(os.path.join(results_dir, "manifest.json"), encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError):
        return None
    for key in ("lightmapTexCoord", "lightmap_texcoord"):
        if isinstance(manifest.get(key), int):
            return manifest[key]
    match = re.fullmatch(r"TEXCOORD_(\d+)", str(manifest.get("uv_set", "")))
    return int(match.group(1)) if match else None


def _mesh_texcoord(mesh_json, fallback):
    """Each written primitive names its lightmap set in extras.lightmapTexCoord."""
    for prim in mesh_json["primitives"]:
        n = (prim.get("extras") or {}).get("lightmapTexCoord")
        if isinstance(n, int):
            return n
    return fallback


def _to_blender(v):
    """glTF is +Y up, Blender +Z up (what Blender's exporter converted)."""
    return np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1)


def _build_mesh(doc, mesh_index, scale_offset, texcoord, original):
    """A Blender mesh from one glTF mesh; the lightmap set mapped to atlas
    space with the node's lightmapScaleOffset and flipped to Blender's v-up."""
    mesh_json = doc.json["meshes"][mesh_index]
    positions, normals, corners, face_mat = [], [], [], []
    uv_sets = {}
    materials = []
    base = 0
    for prim in mesh_json["primitives"]:
        if prim.get("mode", glb_reader.TRIANGLES) != glb_reader.TRIANGLES:
            continue  # Luxel writes triangle lists; points and lines carry no lightmap
        attrs = prim["attributes"]
        pos = doc.accessor(attrs["POSITION"])
        idx = doc.indices(prim)
        positions.append(pos)
        normals.append(doc.accessor(attrs["NORMAL"]) if "NORMAL" in attrs else None)
        for key in attrs:
            if key.startswith("TEXCOORD_"):
                uv_sets.setdefault(int(key[9:]), {})[len(positions) - 1] = doc.accessor(attrs[key])
        corners.append(idx + base)
        mat = prim.get("material")
        mat = doc.json["materials"][mat].get("name") if mat is not None else None
        if mat not in materials:
            materials.append(mat)
        face_mat.append(np.full(len(idx) // 3, materials.index(mat), dtype=np.int32))
        base += len(pos)
    if not positions:
        return None
    counts = [len(p) for p in positions]
    verts = _to_blender(np.concatenate(positions))
    loops = np.concatenate(corners)

    mesh = bpy.data.meshes.new(original.name + "_lightmapped")
    mesh.vertices.add(len(verts))
    mesh.vertices.foreach_set("co", verts.astype(np.float32).ravel())
    mesh.loops.add(len(loops))
    mesh.loops.foreach_set("vertex_index", loops.astype(np.int32))
    n_faces = len(loops) // 3
    mesh.polygons.add(n_faces)
    mesh.polygons.foreach_set("loop_start", np.arange(0, len(loops), 3, dtype=np.int32))
    mesh.polygons.foreach_set("material_index", np.concatenate(face_mat))
    for name in materials:
        mesh.materials.append(bpy.data.materials.get(name) if name else None)

    def per_vertex(arrays, width):
        """One array over all vertices; zeros for primitives without the set."""
        return np.concatenate([arrays.get(i, np.zeros((c, width), np.float32))
                               for i, c in enumerate(counts)])

    old_names = [layer.name for layer in original.uv_layers] if original else []
    sx, sy, ox, oy = scale_offset
    for n in sorted(uv_sets):
        uv = per_vertex(uv_sets[n], 2)
        if n == texcoord:
            uv = uv * np.float32((sx, sy)) + np.float32((ox, oy))
            name = LIGHTMAP_UV
        else:
            name = old_names[n] if n < len(old_names) else f"UVMap.{n:03d}" if n else "UVMap"
        corner_uv = uv[loops]
        corner_uv[:, 1] = 1.0 - corner_uv[:, 1]  # glTF v runs down, Blender's up
        layer = mesh.uv_layers.new(name=name)
        layer.data.foreach_set("uv", corner_uv.astype(np.float32).ravel())
    if texcoord not in uv_sets:
        bpy.data.meshes.remove(mesh)
        raise RuntimeError(f"mesh '{mesh_json.get('name', mesh_index)}' has no TEXCOORD_{texcoord} "
                           "(its lightmap UVs) in the written glTF")
    if mesh.uv_layers:
        mesh.uv_layers[0].active_render = True
    mesh.validate(clean_customdata=False)
    mesh.update()
    if all(n is not None for n in normals):
        # The normals Luxel baked with, as custom normals: smooth faces and
        # hard edges come out as they were exported.
        mesh.polygons.foreach_set("use_smooth", np.ones(n_faces, dtype=bool))
        mesh.normals_split_custom_set_from_vertices(_to_blender(np.concatenate(normals)).tolist())
    return mesh


def apply_uvs(results_dir, glb_path):
    """Gives every object named by a node of the written glTF the baked mesh.
    Returns (objects changed, warnings)."""
    doc = glb_reader.Glb(glb_path)
    fallback = _manifest_texcoord(results_dir)
    fallback = 1 if fallback is None else fallback
    changed, warnings = [], []
    for node in doc.json.get("nodes", []):
        if "mesh" not in node:
            continue
        obj = bpy.data.objects.get(node.get("name", ""))
        if obj is None or obj.type != "MESH":
            warnings.append(f"node '{node.get('name')}' matches no mesh object; left out")
            continue
        extras = node.get("extras") or {}
        scale_offset = extras.get("lightmapScaleOffset", [1.0, 1.0, 0.0, 0.0])
        if "lightmapScaleOffsets" in extras:
            warnings.append(f"'{obj.name}': GPU-instanced nodes are not supported; first instance used")
            scale_offset = extras["lightmapScaleOffsets"][0]
        if extras.get("lightmapIndex", 0):
            warnings.append(f"'{obj.name}' is on lightmap page {extras['lightmapIndex']}; "
                            "only page 0 is shown")
        texcoord = _mesh_texcoord(doc.json["meshes"][node["mesh"]], fallback)
        original = bpy.data.meshes.get(obj.get(ORIGINAL_MESH_PROP, "")) or obj.data
        mesh = _build_mesh(doc, node["mesh"], scale_offset, texcoord, original)
        if mesh is None:
            continue
        previous = obj.data
        original.use_fake_user = True
        obj[ORIGINAL_MESH_PROP] = original.name
        obj.data = mesh
        if previous is not original and previous.users == 0:
            bpy.data.meshes.remove(previous)  # an earlier bake's mesh
        changed.append(obj)
    return changed, warnings


# ---------------------------------------------------------------- materials

def _input_source(node_tree, socket):
    """(output socket linked into ``socket``, or None; its default value)."""
    if socket.is_linked:
        return socket.links[0].from_socket, None
    return None, tuple(socket.default_value)


def _socket(sockets, name, kind):
    """The Mix node has one socket per data type under each name."""
    return next(s for s in sockets if s.name == name and s.type == kind)


def _remove_luxel_nodes(node_tree):
    """Undoes an earlier wiring, reconnecting the original surface shader."""
    nodes, links = node_tree.nodes, node_tree.links
    mix = nodes.get(_NODE_PREFIX + "Mix")
    if mix is not None:
        original = mix.inputs[1].links[0].from_socket if mix.inputs[1].is_linked else None
        targets = [link.to_socket for link in mix.outputs[0].links]
        for target in targets:
            if original is not None:
                links.new(original, target)
    for node in [n for n in nodes if n.name.startswith(_NODE_PREFIX)]:
        nodes.remove(node)


@contextlib.contextmanager
def original_surfaces():
    """Materials as they were before any wiring, for the glTF export: the
    exporter follows the output's links, and through the Luxel nodes it
    would export the lightmap as emission, which the next bake would then
    take for light sources."""
    rewired = []
    for material in bpy.data.materials:
        tree = material.node_tree
        mix = tree.nodes.get(_NODE_PREFIX + "Mix") if tree else None
        if mix is None or not mix.inputs[1].is_linked:
            continue
        original = mix.inputs[1].links[0].from_socket
        for target in [link.to_socket for link in mix.outputs[0].links]:
            tree.links.new(original, target)
            rewired.append((tree, mix, target))
    try:
        yield
    finally:
        for tree, mix, target in rewired:
            tree.links.new(mix.outputs[0], target)


def wire_material(material, image, baked_only=True):
    """surface = mix(original, emission(lightmap x base colour / pi + own
    emission), factor): irradiance E times albedo over pi is the diffuse
    radiance leaving the surface (Luxel's manifest: "outgoing diffuse
    radiance = albedo * E / pi"). The factor (node "Luxel Mix", 1 = baked light
    only) replaces the live shading, because adding the emission to a lit
    BSDF would count the light twice in Cycles and EEVEE."""
    if material.node_tree is None:
        material.use_nodes = True
    tree = material.node_tree
    nodes, links = tree.nodes, tree.links
    _remove_luxel_nodes(tree)
    output = next((n for n in nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output), None)
    if output is None:
        output = nodes.new("ShaderNodeOutputMaterial")
    surface = output.inputs["Surface"]
    original = surface.links[0].from_socket if surface.is_linked else None
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)

    def new(kind, name, x, y):
        node = nodes.new(kind)
        node.name = node.label = _NODE_PREFIX + name
        node.location = (output.location.x - x, output.location.y + y)
        return node

    uv = new("ShaderNodeUVMap", "UV", 1100, -300)
    uv.uv_map = LIGHTMAP_UV
    tex = new("ShaderNodeTexImage", "Lightmap", 900, -300)
    tex.image = image
    tex.interpolation = "Linear"
    tex.extension = "EXTEND"
    links.new(uv.outputs["UV"], tex.inputs["Vector"])

    albedo = new("ShaderNodeMix", "Albedo x Lightmap", 650, -300)
    albedo.data_type = "RGBA"
    albedo.blend_type = "MULTIPLY"
    albedo.inputs["Factor"].default_value = 1.0
    a_in, b_in = (_socket(albedo.inputs, name, "RGBA") for name in ("A", "B"))
    base_link, base_value = (None, (0.8, 0.8, 0.8, 1.0))
    if bsdf is not None:
        base_link, base_value = _input_source(tree, bsdf.inputs["Base Color"])
    if base_link is not None:
        links.new(base_link, a_in)
    else:
        a_in.default_value = base_value
    links.new(tex.outputs["Color"], b_in)

    radiance = new("ShaderNodeVectorMath", "Over Pi", 450, -300)
    radiance.operation = "SCALE"
    radiance.inputs["Scale"].default_value = 1.0 / math.pi
    links.new(_socket(albedo.outputs, "Result", "RGBA"), radiance.inputs[0])
    total = radiance.outputs["Vector"]

    if bsdf is not None:
        strength = bsdf.inputs["Emission Strength"].default_value
        own_link, own_value = _input_source(tree, bsdf.inputs["Emission Color"])
        if strength > 0 and (own_link is not None or any(own_value[:3])):
            own = new("ShaderNodeVectorMath", "Own Emission", 450, -450)
            own.operation = "SCALE"
            own.inputs["Scale"].default_value = strength
            if own_link is not None:
                links.new(own_link, own.inputs[0])
            else:
                own.inputs[0].default_value = own_value[:3]
            add = new("ShaderNodeVectorMath", "Add Emission", 280, -350)
            add.operation = "ADD"
            links.new(total, add.inputs[0])
            links.new(own.outputs["Vector"], add.inputs[1])
            total = add.outputs["Vector"]

    emission = new("ShaderNodeEmission", "Baked Light", 150, -300)
    emission.inputs["Strength"].default_value = 1.0
    links.new(total, emission.inputs["Color"])
    mix = new("ShaderNodeMixShader", "Mix", 0, 150)
    mix.inputs["Fac"].default_value = 1.0 if baked_only else 0.0
    if original is not None:
        links.new(original, mix.inputs[1])
    links.new(emission.outputs["Emission"], mix.inputs[2])
    links.new(mix.outputs["Shader"], surface)


def use_existing_uvs(results_dir, exported_glb):
    """A bake that used the scene's own lightmap UVs (TEXCOORD_1, e.g. the
    layer an earlier bake added) writes no geometry back: the objects keep
    their meshes, and the set Luxel baked is copied to the layer the
    materials read when it has another name."""
    texcoord = _manifest_texcoord(results_dir)
    texcoord = 1 if texcoord is None else texcoord
    objects, warnings = [], []
    for node in glb_reader.Glb(exported_glb).json.get("nodes", []):
        obj = bpy.data.objects.get(node.get("name", "")) if "mesh" in node else None
        if obj is None or obj.type != "MESH":
            continue
        layers = obj.data.uv_layers
        if texcoord >= len(layers):
            warnings.append(f"'{obj.name}' has no UV layer {texcoord + 1} (TEXCOORD_{texcoord}); left out")
            continue
        source = layers[texcoord]
        if source.name != LIGHTMAP_UV:
            target = layers.get(LIGHTMAP_UV) or layers.new(name=LIGHTMAP_UV, do_init=False)
            source = obj.data.uv_layers[texcoord]  # new() may move the collection's storage
            uv = np.empty(len(source.data) * 2, dtype=np.float32)
            source.data.foreach_get("uv", uv)
            target.data.foreach_set("uv", uv)
        objects.append(obj)
    return objects, warnings


def lightmap_file(results_dir):
    """The map to show: the denoised one when the bake wrote it (the default
    denoiser, docs/api.md "Denoised lightmap"), else the raw irradiance.exr."""
    denoised = os.path.join(results_dir, "irradiance_denoised.exr")
    return denoised if os.path.isfile(denoised) else os.path.join(results_dir, "irradiance.exr")


def apply_results(results_dir, lightmapped_glb, exported_glb, baked_only=True):
    """Lightmap image + UVs + materials. ``lightmapped_glb``: Luxel's
    write-back, None when the bake used the scene's own UVs (then
    ``exported_glb``, the scene as sent, names the objects). Returns
    (objects, warnings)."""
    image = lightmap_image(lightmap_file(results_dir))
    if lightmapped_glb:
        objects, warnings = apply_uvs(results_dir, lightmapped_glb)
    else:
        objects, warnings = use_existing_uvs(results_dir, exported_glb)
    _own_materials(objects)
    done = set()
    for obj in objects:
        for slot in obj.material_slots:
            mat = slot.material
            if mat is not None and mat.name not in done:
                wire_material(mat, image, baked_only)
                done.add(mat.name)
    return objects, warnings


def _own_materials(objects):
    """Baked objects get their own copy ("<name> (Luxel)") of any material
    that objects outside the bake also use: those have no LuxelLightmap
    layer, and the wired material would show them black."""
    baked = {o.name for o in objects}
    outside = {slot.material.name for o in bpy.data.objects if o.name not in baked
               for slot in getattr(o, "material_slots", []) if slot.material is not None}
    copies = {}
    for obj in objects:
        for i, mat in enumerate(obj.data.materials):
            if mat is None or mat.name not in outside:
                continue
            if mat.name not in copies:
                name = mat.name + " (Luxel)"
                copies[mat.name] = bpy.data.materials.get(name) or mat.copy()
                copies[mat.name].name = name
            obj.data.materials[i] = copies[mat.name]


def restore_original(obj):
    """Gives an object back the mesh it had before its first bake."""
    original = bpy.data.meshes.get(obj.get(ORIGINAL_MESH_PROP, ""))
    if original is None:
        return False
    baked = obj.data
    obj.data = original
    del obj[ORIGINAL_MESH_PROP]
    if not any(o.get(ORIGINAL_MESH_PROP) == original.name for o in bpy.data.objects):
        original.use_fake_user = False
    if baked.users == 0:
        bpy.data.meshes.remove(baked)
    return True
