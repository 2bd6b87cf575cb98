#!/usr/bin/env python3
"""Writes the seed corpus of import_fuzz (tests/fuzz/corpus/): a few tiny
.gltf/.glb files covering the importer's features. Re-run after changing it:
    python3 tests/fuzz/make_corpus.py
"""
import base64, json, os, struct, zlib

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")


def png_rgba(w, h, pixels):
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    raw = b"".join(b"\0" + bytes(pixels[y * w * 4:(y + 1) * w * 4]) for y in range(h))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


class Doc:
    def __init__(self):
        self.bin = bytearray()
        self.j = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}],
                  "nodes": [], "meshes": [], "accessors": [], "bufferViews": []}

    def view(self, data, stride=0):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        self.bin += data
        self.j["bufferViews"].append(v)
        return len(self.j["bufferViews"]) - 1

    def acc(self, data, ctype, count, typ, normalized=False):
        a = {"bufferView": self.view(data), "componentType": ctype, "count": count, "type": typ}
        if normalized:
            a["normalized"] = True
        self.j["accessors"].append(a)
        return len(self.j["accessors"]) - 1

    def quad(self, index_type=5125, uv1=True, uv0=False, normals=False):
        pos = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0]
        prim = {"attributes": {"POSITION": self.acc(struct.pack("<12f", *pos), 5126, 4, "VEC3")}}
        if uv1:
            prim["attributes"]["TEXCOORD_1"] = self.acc(struct.pack("<8f", 0, 0, .1, 0, .1, .1, 0, .1), 5126, 4, "VEC2")
        if uv0:
            prim["attributes"]["TEXCOORD_0"] = self.acc(struct.pack("<8H", 0, 0, 65535, 0, 65535, 65535, 0, 65535),
                                                        5123, 4, "VEC2", True)
        if normals:
            prim["attributes"]["NORMAL"] = self.acc(struct.pack("<12f", *([0, 0, 1] * 4)), 5126, 4, "VEC3")
        idx = [0, 1, 2, 0, 2, 3]
        if index_type:
            fmt = {5121: "<6B", 5123: "<6H", 5125: "<6I"}[index_type]
            prim["indices"] = self.acc(struct.pack(fmt, *idx), index_type, 6, "SCALAR")
        return prim

    def mesh(self, prims, name="m"):
        self.j["meshes"].append({"name": name, "primitives": prims})
        return len(self.j["meshes"]) - 1

    def node(self, n, root=True):
        self.j["nodes"].append(n)
        i = len(self.j["nodes"]) - 1
        if root:
            self.j["scenes"][0]["nodes"].append(i)
        return i

    def gltf(self):
        j = dict(self.j)
        j["buffers"] = [{"byteLength": len(self.bin), "uri": "data:application/octet-stream;base64,"
                         + base64.b64encode(bytes(self.bin)).decode()}]
        return json.dumps(j, separators=(",", ":")).encode()

    def glb(self):
        j = dict(self.j)
        j["buffers"] = [{"byteLength": len(self.bin)}]
        js = json.dumps(j, separators=(",", ":")).encode()
        js += b" " * (-len(js) % 4)
        b = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        total = 12 + 8 + len(js) + 8 + len(b)
        return (b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(js)) + b"JSON" + js
                + struct.pack("<I", len(b)) + b"BIN\0" + b)


def main():
    os.makedirs(OUT, exist_ok=True)
    files = {}

    d = Doc()
    d.node({"mesh": d.mesh([d.quad(5121)])})
    files["indexed_u8.gltf"] = d.gltf()
    files["indexed_u8.glb"] = d.glb()

    d = Doc()
    m = d.mesh([d.quad(0, normals=True), dict(d.quad(5123), mode=5)])
    c = d.node({"mesh": m, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1]}, root=False)
    d.node({"children": [c], "translation": [1, 2, 3], "rotation": [0, 0.7071068, 0, 0.7071068], "scale": [2, 2, 2]})
    d.node({"mesh": m})
    files["hierarchy_instancing.gltf"] = d.gltf()

    d = Doc()
    img = png_rgba(2, 2, [255, 128, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0, 10, 20, 30, 40])
    d.j["images"] = [{"bufferView": d.view(img), "mimeType": "image/png"}]
    d.j["textures"] = [{"source": 0}]
    d.j["materials"] = [{"name": "mat", "pbrMetallicRoughness": {
        "baseColorFactor": [1, 0.5, 0.5, 1], "baseColorTexture": {"index": 0},
        "metallicRoughnessTexture": {"index": 0, "texCoord": 1}, "metallicFactor": 0, "roughnessFactor": 0.5},
        "emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0},
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
        "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": True}]
    p = d.quad(5125, uv0=True)
    p["material"] = 0
    d.node({"mesh": d.mesh([p])})
    files["material_texture.glb"] = d.glb()

    d = Doc()
    d.j["extensionsUsed"] = ["KHR_lights_punctual"]
    d.j["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 10, "color": [1, 1, 1], "range": 5},
        {"type": "spot", "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.7}},
        {"type": "directional", "intensity": 2}]}}
    for i in range(3):
        d.node({"translation": [i, 1, 0], "extensions": {"KHR_lights_punctual": {"light": i}}})
    d.node({"mesh": d.mesh([d.quad(5123)])})
    files["lights.gltf"] = d.gltf()

    d = Doc()
    p = d.quad(5125)
    base = p["attributes"]["POSITION"]
    d.j["accessors"][base]["sparse"] = {"count": 1, "indices": {"bufferView": d.view(struct.pack("<I", 2)),
                                                                "componentType": 5125},
                                        "values": {"bufferView": d.view(struct.pack("<3f", 2, 2, 0))}}
    d.node({"mesh": d.mesh([p])})
    files["sparse.gltf"] = d.gltf()

    files["empty.gltf"] = b'{"asset":{"version":"2.0"}}'

    # Triangle fan (the strip is in hierarchy_instancing.gltf) and points.
    d = Doc()
    d.node({"mesh": d.mesh([dict(d.quad(0), mode=6), dict(d.quad(5121), mode=6), dict(d.quad(0), mode=0)])})
    files["fan_points.gltf"] = d.gltf()

    # KHR_mesh_quantization: short positions, byte normals, ubyte lightmap UVs.
    d = Doc()
    d.j["extensionsUsed"] = d.j["extensionsRequired"] = ["KHR_mesh_quantization"]
    prim = {"attributes": {
        "POSITION": d.acc(struct.pack("<16h", 0, 0, 0, 0, 9, 0, 0, 0, 9, 9, 0, 0, 0, 9, 0, 0), 5122, 4, "VEC3"),
        "NORMAL": d.acc(struct.pack("<16b", *([0, 0, 127, 0] * 4)), 5120, 4, "VEC3", True),
        "TEXCOORD_1": d.acc(struct.pack("<8B", 0, 0, 1, 0, 1, 1, 0, 1), 5121, 4, "VEC2")},
        "indices": d.acc(struct.pack("<6B", 0, 1, 2, 0, 2, 3), 5121, 6, "SCALAR")}
    d.j["bufferViews"][d.j["accessors"][prim["attributes"]["POSITION"]]["bufferView"]]["byteStride"] = 8
    d.j["bufferViews"][d.j["accessors"][prim["attributes"]["NORMAL"]]["bufferView"]]["byteStride"] = 4
    d.node({"mesh": d.mesh([prim])})
    files["quantized.glb"] = d.glb()

    # EXT_mesh_gpu_instancing: 3 instances with translation, rotation, scale.
    d = Doc()
    d.j["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    t = d.acc(struct.pack("<9f", 0, 0, 0, 2, 0, 0, 4, 0, 0), 5126, 3, "VEC3")
    r = d.acc(struct.pack("<12h", 0, 0, 0, 32767, 0, 0, 23170, 23170, 0, 0, 0, 32767), 5122, 3, "VEC4", True)
    sc = d.acc(struct.pack("<9f", 1, 1, 1, 2, 2, 2, 1, 1, 1), 5126, 3, "VEC3")
    d.node({"mesh": d.mesh([d.quad(5123)]), "translation": [0, 1, 0], "extensions": {
        "EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": t, "ROTATION": r, "SCALE": sc}}}})
    files["gpu_instancing.gltf"] = d.gltf()

    # Sparse-only accessors: indices and TEXCOORD_0 without a bufferView.
    d = Doc()
    p = d.quad(0)
    idx = {"componentType": 5123, "count": 6, "type": "SCALAR", "sparse": {
        "count": 5, "indices": {"bufferView": d.view(struct.pack("<5B", 1, 2, 3, 4, 5)), "componentType": 5121},
        "values": {"bufferView": d.view(struct.pack("<5H", 1, 2, 0, 2, 3))}}}
    d.j["accessors"].append(idx)
    p["indices"] = len(d.j["accessors"]) - 1
    d.j["accessors"].append({"componentType": 5126, "count": 4, "type": "VEC2"})
    p["attributes"]["TEXCOORD_0"] = len(d.j["accessors"]) - 1
    d.node({"mesh": d.mesh([p])})
    files["sparse_only.glb"] = d.glb()

    # Lightmap UV generation seeds (no TEXCOORD_1): a closed octahedron with
    # shared vertices and one with a non-manifold fin, used once and
    # instanced twice at different scales.
    d = Doc()
    pos = [1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0.5, 2]
    idx = [0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5, 0, 2, 6]
    prim = {"attributes": {"POSITION": d.acc(struct.pack("<21f", *pos), 5126, 7, "VEC3")},
            "indices": d.acc(struct.pack("<27H", *idx), 5123, 27, "SCALAR")}
    closed = {"attributes": prim["attributes"], "indices": d.acc(struct.pack("<24H", *idx[:24]), 5123, 24, "SCALAR")}
    d.node({"mesh": d.mesh([prim], "fin")})
    solid = d.mesh([closed], "octahedron")
    d.node({"mesh": solid, "translation": [4, 0, 0]})
    d.node({"mesh": solid, "translation": [8, 0, 0], "scale": [3, 1, 2]})
    files["uv_generate.glb"] = d.glb()

    for name, data in files.items():
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(data)
        print(name, len(data))


if __name__ == "__main__":
    main()
