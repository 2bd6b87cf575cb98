"""The write-back round trip through real third-party readers.

Every source scene (corpus.py, plus any --scene given) is baked with
generated lightmap UVs (`luxel bake --local --uv generate`), and the written
`<scene>_lightmapped.glb` is read by
  - Blender 5.0.1's glTF importer (bpy), and
  - Assimp 5.2 from Debian (`assimp info` of assimp-utils, and libassimp
    through assimp_dump.cpp for the data).
Checked for every written file, in both readers:
  - it imports;
  - every mesh has its lightmap UVs in the set the primitive records
    (extras.lightmapTexCoord), all inside [0,1]^2 and spanning an area;
  - every UV set of the source arrives unchanged: per set, the multiset of
    (corner position, corner UV) equals the source's (seam copies repeat a
    source vertex, so multisets compare where vertex lists cannot);
  - every material's textures read the same UV set as in the source;
and baking the written file again with --uv existing gives the same
irradiance bits as the first bake.
Run with the bpy venv's python (tests/support/install-test-tools.sh).
"""
import argparse
import collections
import json
import os
import struct
import subprocess
import sys
import unittest

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import corpus  # noqa: E402

ARGS = None
BAKE = ["--local", "--resolution", "64", "--samples", "4", "--sky", "1,1,1"]


def glb_json(path):
    with open(path, "rb") as f:
        data = f.read()
    length, = struct.unpack_from("<I", data, 12)
    return json.loads(data[20:20 + length])


def luxel_bake(scene, out, uv):
    cmd = [ARGS.luxel, "bake", scene, "--out", out, "--uv", uv] + BAKE
    run = subprocess.run(cmd, capture_output=True, text=True)
    return run.returncode, run.stdout + run.stderr


def exr_pixels(path):
    image = bpy.data.images.load(path)
    pixels = list(image.pixels)
    bpy.data.images.remove(image)
    return pixels


# Blender -------------------------------------------------------------------


def blender_import(path):
    """Per mesh datablock: UV layer names and per-layer corner multisets;
    per material: (image, UV layer read) of every image texture node."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    meshes, materials = {}, {}
    for obj in bpy.data.objects:
        if obj.type != "MESH" or obj.data.name in meshes:
            continue
        me = obj.data
        corners = [tuple(round(c, 4) for c in me.vertices[loop.vertex_index].co) for loop in me.loops]
        layers = []
        for layer in me.uv_layers:
            # Exact values for the range checks, rounded ones for the sets.
            uvs = [(d.uv[0], d.uv[1]) for d in layer.data]
            rounded = [(round(u, 5), round(v, 5)) for u, v in uvs]
            layers.append((layer.name, uvs, collections.Counter(zip(corners, rounded))))
        meshes[me.name] = layers
    for mat in bpy.data.materials:
        if not mat.node_tree:
            continue
        reads = []
        for node in mat.node_tree.nodes:
            if node.type != "TEX_IMAGE":
                continue
            uv = ""
            vector = node.inputs["Vector"]
            if vector.is_linked:
                src = vector.links[0].from_node
                while src.type != "UVMAP" and any(i.is_linked for i in src.inputs):
                    src = next(i for i in src.inputs if i.is_linked).links[0].from_node
                uv = src.uv_map if src.type == "UVMAP" else src.type
            reads.append((node.image.name if node.image else "", uv))
        materials[mat.name] = sorted(reads)
    return meshes, materials


# Assimp --------------------------------------------------------------------


def assimp_import(path):
    """Assimp's reading: `assimp info` (assimp-utils) must accept the file, and
    assimp_dump (libassimp) gives per mesh (one per glTF primitive) its UV
    channels with their corner multisets and per material the UV channel
    each texture reads."""
    info = subprocess.run(["assimp", "info", path], capture_output=True, text=True)
    if info.returncode != 0:
        return None, (info.stdout + info.stderr).strip().splitlines()[-1:]
    run = subprocess.run([ARGS.assimp_dump, path], capture_output=True, text=True)
    if run.returncode != 0:
        return None, run.stderr.strip().splitlines()[-1:]
    doc = json.loads(run.stdout)
    meshes = []
    for m in doc["meshes"]:
        v = m["vertices"]
        pos = [tuple(round(c, 4) for c in v[3 * i:3 * i + 3]) for i in range(len(v) // 3)]
        corners = [i for face in m["faces"] for i in face]
        sets = []
        for channel in m["uv"]:
            # Exact values for the range checks, rounded ones for the sets.
            uv = [(channel[2 * i], channel[2 * i + 1]) for i in range(len(channel) // 2)]
            rounded = [(round(u, 5), round(v, 5)) for u, v in uv]
            sets.append((uv, collections.Counter((pos[i], rounded[i]) for i in corners)))
        meshes.append((m["name"], sets))
    return (meshes, [sorted(map(tuple, mat)) for mat in doc["materials"]]), None


def in_unit_square(uvs):
    return all(-1e-5 <= u <= 1 + 1e-5 and -1e-5 <= v <= 1 + 1e-5 for u, v in uvs)


def spans_area(uvs):
    """Not collapsed to a point or a line. (Charts of small meshes on many
    small pages span a few texels of a tall stacked atlas: no absolute size
    is asked.)"""
    us, vs = [u for u, _ in uvs], [v for _, v in uvs]
    return bool(uvs) and max(us) > min(us) and max(vs) > min(vs)


class RoundTrip(unittest.TestCase):
    results = {}

    @classmethod
    def setUpClass(cls):
        os.makedirs(ARGS.work, exist_ok=True)
        cls.sources = corpus.make(os.path.join(ARGS.work, "sources")) + list(ARGS.scene or [])

    def check_one(self, source):
        name = os.path.splitext(os.path.basename(source))[0]
        out = os.path.join(ARGS.work, "out", name)
        problems = []
        rc, log = luxel_bake(source, out, "generate")
        if rc != 0:
            return [f"bake refused: {log.strip().splitlines()[-1] if log.strip() else rc}"]
        written = os.path.join(out, name + "_lightmapped.glb")
        if not os.path.exists(written):
            return ["no _lightmapped.glb written"]
        doc = glb_json(written)
        # Lightmap set per mesh under the name Blender gives it (the glTF
        # name, else "Mesh_<index>"), and per primitive under the name Assimp
        # gives it (the name, else "meshes[<index>]", then "-<primitive>" when
        # the mesh has several).
        lightmap_by_mesh, lightmap_by_prim = {}, {}
        for i, mesh in enumerate(doc["meshes"]):
            prims = mesh["primitives"]
            for p, prim in enumerate(prims):
                index = prim.get("extras", {}).get("lightmapTexCoord")
                assimp_name = (mesh.get("name") or f"meshes[{i}]") + (f"-{p}" if len(prims) > 1 else "")
                lightmap_by_prim[assimp_name] = index
                if index is not None:
                    lightmap_by_mesh.setdefault(mesh.get("name") or f"Mesh_{i}", set()).add(index)

        # `luxel inspect` and the manifest say which set holds the lightmap.
        counts = collections.Counter(i for i in lightmap_by_prim.values() if i is not None)
        inspect = subprocess.run([ARGS.luxel, "inspect", written, "--no-trace"],
                                 capture_output=True, text=True)
        line = next((l for l in inspect.stdout.splitlines() if l.startswith("lightmap set ")), "")
        for index, count in counts.items():
            if f"TEXCOORD_{index} on {count} primitive" not in line:
                problems.append(f"luxel inspect: '{line}' does not say TEXCOORD_{index} on {count}")
        with open(os.path.join(out, "manifest.json")) as f:
            manifest_sets = json.load(f).get("uv_sets", {})
        if manifest_sets != {f"TEXCOORD_{i}": c for i, c in counts.items()}:
            problems.append(f"manifest uv_sets {manifest_sets}, file {dict(counts)}")

        # Blender.
        src_meshes, src_mats = blender_import(source)
        out_meshes, out_mats = blender_import(written)
        for mesh_name, indices in lightmap_by_mesh.items():
            layers = out_meshes.get(mesh_name)
            if layers is None:
                problems.append(f"Blender: mesh '{mesh_name}' missing")
                continue
            for index in indices:
                if index >= len(layers):
                    problems.append(f"Blender: mesh '{mesh_name}' has {len(layers)} UV layers, "
                                    f"lightmap is TEXCOORD_{index}")
                elif not in_unit_square(layers[index][1]) or not spans_area(layers[index][1]):
                    problems.append(f"Blender: mesh '{mesh_name}' lightmap UVs outside [0,1]^2 "
                                    "or degenerate")
            for k, (layer_name, _, counter) in enumerate(src_meshes.get(mesh_name, [])):
                if k >= len(layers) or layers[k][0] != layer_name or layers[k][2] != counter:
                    problems.append(f"Blender: mesh '{mesh_name}' UV set {k} ('{layer_name}') changed")
        for mat_name, reads in src_mats.items():
            if out_mats.get(mat_name) != reads:
                problems.append(f"Blender: material '{mat_name}' textures read {out_mats.get(mat_name)}"
                                f", source {reads}")

        # Assimp.
        src_a, _ = assimp_import(source)
        out_a, error = assimp_import(written)
        if out_a is None:
            problems.append(f"Assimp refuses the written file: {error}")
        else:
            meshes, materials = out_a
            # Assimp reads the default scene's meshes only.
            for mesh_name, sets in meshes:
                if mesh_name not in lightmap_by_prim:
                    problems.append(f"Assimp: mesh '{mesh_name}' is not a primitive of the file")
                    continue
                index = lightmap_by_prim[mesh_name]
                if index is None:
                    continue
                if index >= len(sets):
                    problems.append(f"Assimp: '{mesh_name}' has {len(sets)} UV channels, "
                                    f"lightmap is TEXCOORD_{index}")
                elif not in_unit_square(sets[index][0]) or not spans_area(sets[index][0]):
                    problems.append(f"Assimp: '{mesh_name}' lightmap UVs outside [0,1]^2")
            if src_a is not None:
                src_meshes_a, src_materials_a = src_a
                if src_materials_a != materials[:len(src_materials_a)]:
                    problems.append("Assimp: material UV sources changed")
                written_sets = dict(meshes)
                for mesh_name, src_sets in src_meshes_a:
                    sets = written_sets.get(mesh_name)
                    if sets is None:
                        problems.append(f"Assimp: mesh '{mesh_name}' of the source is missing")
                        continue
                    for k, (_, counter) in enumerate(src_sets):
                        if k >= len(sets) or sets[k][1] != counter:
                            problems.append(f"Assimp: '{mesh_name}' UV channel {k} changed")

        # The written file bakes to the same bits.
        again = os.path.join(ARGS.work, "again", name)
        rc, log = luxel_bake(written, again, "existing")
        if rc != 0:
            problems.append(f"--uv existing refused the written file: {log.strip().splitlines()[-1]}")
        else:
            # One irradiance.exr, or irradiance_<page>.exr per lightmap page.
            pages = sorted(f for f in os.listdir(out)
                           if f.startswith("irradiance") and f.endswith(".exr") and "denoised" not in f)
            if not pages or sorted(f for f in os.listdir(again) if f in pages) != pages:
                problems.append(f"--uv existing on the written file wrote other pages than {pages}")
            elif any(exr_pixels(os.path.join(out, f)) != exr_pixels(os.path.join(again, f))
                     for f in pages):
                problems.append("--uv existing on the written file gives other irradiance bits")
        return problems

    def test_every_written_file(self):
        failed = {}
        for source in self.sources:
            problems = self.check_one(source)
            name = os.path.basename(source)
            print(f"{'ok  ' if not problems else 'FAIL'} {name}", flush=True)
            for p in problems:
                print(f"       {p}", flush=True)
            self.results[name] = problems
            if problems:
                failed[name] = problems
        if ARGS.report:
            with open(ARGS.report, "w") as f:
                json.dump(self.results, f, indent=1)
        print(f"{len(self.sources) - len(failed)} of {len(self.sources)} written files round-trip "
              "in Blender and Assimp", flush=True)
        self.assertEqual(failed, {})

    def injected(self, case, edit):
        """Bakes corpus case `case`, applies `edit` to the written file's
        JSON and returns (source, edited written file)."""
        source = next(s for s in self.sources if os.path.basename(s) == case)
        name = os.path.splitext(case)[0]
        out = os.path.join(ARGS.work, "injected", name)
        rc, log = luxel_bake(source, out, "generate")
        self.assertEqual(rc, 0, log)
        written = os.path.join(out, name + "_lightmapped.glb")
        with open(written, "rb") as f:
            data = f.read()
        length, = struct.unpack_from("<I", data, 12)
        doc = json.loads(data[20:20 + length])
        edit(doc)
        text = json.dumps(doc).encode()
        text += b" " * (-len(text) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text + data[20 + length:]
        with open(written, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
        return source, written

    def test_injected_overwrite_is_caught(self):
        """What the write-back once did to Khronos' MultiUVTest: the lightmap
        replaces the TEXCOORD_1 a material reads. The check must see it."""
        def overwrite(doc):
            prim = doc["meshes"][0]["primitives"][0]
            self.assertEqual(prim["extras"]["lightmapTexCoord"], 2)
            prim["attributes"]["TEXCOORD_1"] = prim["attributes"].pop("TEXCOORD_2")
            prim["extras"]["lightmapTexCoord"] = 1
        source, written = self.injected("two_uv_sets.glb", overwrite)
        src_meshes, _ = blender_import(source)
        out_meshes, _ = blender_import(written)
        self.assertNotEqual(src_meshes["logo_cube"][1][2], out_meshes["logo_cube"][1][2])

    def test_injected_gap_is_caught(self):
        """What the write-back once did to Khronos' Box: TEXCOORD_1 without
        TEXCOORD_0. Blender's importer drops the set, so the check must fail."""
        def gap(doc):
            for mesh in doc["meshes"]:
                for prim in mesh["primitives"]:
                    prim["attributes"].pop("TEXCOORD_0")
        _, written = self.injected("box_no_uv.glb", gap)
        meshes, _ = blender_import(written)
        self.assertLess(len(meshes["box"]), 2, "Blender kept a set after a gap")


def main():
    global ARGS
    parser = argparse.ArgumentParser()
    parser.add_argument("--luxel", required=True)
    parser.add_argument("--assimp-dump", required=True, help="tests/roundtrip/assimp_dump")
    parser.add_argument("--work", required=True)
    parser.add_argument("--scene", action="append", help="another source scene to round-trip")
    parser.add_argument("--report", help="write per-file problems as JSON here")
    ARGS, rest = parser.parse_known_args()
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)


if __name__ == "__main__":
    main()
