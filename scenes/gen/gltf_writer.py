"""glTF 2.0 writer (numpy + stdlib only): bufferViews and accessors (separate,
shared or interleaved), materials, meshes, nodes, cameras, embedded PNG images,
and output as .glb or as .gltf with an external .bin.

Determinism: JSON is emitted in insertion order and PNGs are written with zlib
level 9, so the same calls give byte-identical files on one machine. Every
bufferView starts on a 4-byte boundary; POSITION accessors carry exact min/max.
"""
import json
import os
import struct
import zlib

import numpy as np

# glTF / GL enums
BYTE, UBYTE, SHORT, USHORT, UINT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
NEAREST, LINEAR, LINEAR_MIPMAP_LINEAR = 9728, 9729, 9987
REPEAT, CLAMP_TO_EDGE = 10497, 33071

DTYPE_TO_COMP = {np.dtype(np.float32): FLOAT, np.dtype(np.uint8): UBYTE,
                 np.dtype(np.uint16): USHORT, np.dtype(np.uint32): UINT}
NCOMP_TO_TYPE = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}


# ----------------------------------------------------------------------------
# PNG writer (zlib + struct only)
# ----------------------------------------------------------------------------
def png_bytes(img):
    img = np.ascontiguousarray(img, dtype=np.uint8)
    h, w, c = img.shape
    color_type = {3: 2, 4: 6}[c]
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))  # filter 0 per row

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, color_type, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


# ----------------------------------------------------------------------------
# glTF writer
# ----------------------------------------------------------------------------
class GltfWriter:
    def __init__(self, name):
        self.j = {"asset": {"version": "2.0", "generator": "Luxel scenes/generate_scenes.py"},
                  "extensionsUsed": [], "scene": 0, "scenes": [{"name": name, "nodes": []}],
                  "nodes": [], "meshes": [], "materials": [], "accessors": [], "bufferViews": [],
                  "buffers": []}
        self.view_data = []   # bytes per bufferView (index-aligned with j["bufferViews"])
        self.shared = {}      # key -> bufferView index (accessors appended into one view)

    # -- buffer views / accessors ------------------------------------------
    def view(self, data, target=None, stride=None):
        bv = {"buffer": 0, "byteOffset": 0, "byteLength": 0}
        if stride is not None:
            bv["byteStride"] = stride
        if target is not None:
            bv["target"] = target
        self.j["bufferViews"].append(bv)
        self.view_data.append(bytearray(data))
        return len(self.j["bufferViews"]) - 1

    def accessor(self, arr, target, shared_key=None, minmax=False):
        arr = np.ascontiguousarray(arr)
        ncomp = 1 if arr.ndim == 1 else arr.shape[1]
        data = arr.tobytes()
        if shared_key is None:
            vi, off = self.view(data, target), 0
        else:
            if shared_key not in self.shared:
                self.shared[shared_key] = self.view(b"", target)
            vi = self.shared[shared_key]
            buf = self.view_data[vi]
            off = len(buf)
            buf += data + b"\x00" * ((-len(data)) % 4)   # keep every accessor 4-aligned
        acc = {"bufferView": vi, "componentType": DTYPE_TO_COMP[arr.dtype],
               "count": int(arr.shape[0]), "type": NCOMP_TO_TYPE[ncomp]}
        if off:
            acc["byteOffset"] = off
        if minmax:
            a2 = arr.reshape(arr.shape[0], ncomp)
            acc["min"] = [float(v) for v in a2.min(axis=0)]
            acc["max"] = [float(v) for v in a2.max(axis=0)]
        self.j["accessors"].append(acc)
        return len(self.j["accessors"]) - 1

    def interleaved(self, named_arrays):
        """One bufferView with byteStride holding all float32 attributes of a
        primitive interleaved; returns {attribute: accessor index}."""
        n = named_arrays[0][1].shape[0]
        cols = [a.reshape(n, -1).astype(np.float32) for _, a in named_arrays]
        block = np.concatenate(cols, axis=1)
        stride = block.shape[1] * 4
        vi = self.view(block.tobytes(), ARRAY_BUFFER, stride)
        out, off = {}, 0
        for (name, _), col in zip(named_arrays, cols):
            acc = {"bufferView": vi, "componentType": FLOAT, "count": n,
                   "type": NCOMP_TO_TYPE[col.shape[1]]}
            if off:
                acc["byteOffset"] = off
            if name == "POSITION":
                acc["min"] = [float(v) for v in col.min(axis=0)]
                acc["max"] = [float(v) for v in col.max(axis=0)]
            self.j["accessors"].append(acc)
            out[name] = len(self.j["accessors"]) - 1
            off += col.shape[1] * 4
        return out

    # -- scene objects -------------------------------------------------------
    def material(self, name, base, metallic=0.0, roughness=1.0, **extra):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": [float(c) for c in base],
                                                    "metallicFactor": metallic,
                                                    "roughnessFactor": roughness}}
        tex = extra.pop("base_texture", None)
        if tex is not None:
            m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": tex, "texCoord": 0}
        m.update(extra)
        self.j["materials"].append(m)
        return len(self.j["materials"]) - 1

    def mesh(self, name, prims, index_dtype=None, shared=False, interleave=False, drop_normals=False):
        out = []
        for p in prims:
            attrs = [("POSITION", p["pos"])]
            if not drop_normals:
                attrs.append(("NORMAL", p["nrm"]))
            attrs += [("TEXCOORD_0", p["uv0"]), ("TEXCOORD_1", p["uv1"])]
            nv = len(p["pos"])
            dt = index_dtype or (np.uint16 if nv <= 65535 else np.uint32)
            assert nv - 1 <= np.iinfo(dt).max
            if interleave:
                amap = self.interleaved(attrs)
            else:
                key = {"POSITION": "pos", "NORMAL": "nrm", "TEXCOORD_0": "uv0", "TEXCOORD_1": "uv1"}
                amap = {nm: self.accessor(a, ARRAY_BUFFER, key[nm] if shared else None, nm == "POSITION")
                        for nm, a in attrs}
            ind = self.accessor(p["idx"].reshape(-1).astype(dt), ELEMENT_ARRAY_BUFFER,
                                ("idx%d" % (8 * np.dtype(dt).itemsize)) if shared else None)
            out.append({"attributes": amap, "indices": ind, "material": p["material"], "mode": 4})
        self.j["meshes"].append({"name": name, "primitives": out})
        return len(self.j["meshes"]) - 1

    def node(self, name, parent=None, **props):
        n = {"name": name}
        n.update(props)
        self.j["nodes"].append(n)
        i = len(self.j["nodes"]) - 1
        if parent is None:
            self.j["scenes"][0]["nodes"].append(i)
        else:
            self.j["nodes"][parent].setdefault("children", []).append(i)
        return i

    def camera(self, name, yfov, aspect, znear, zfar):
        self.j.setdefault("cameras", []).append(
            {"name": name, "type": "perspective",
             "perspective": {"aspectRatio": aspect, "yfov": yfov, "znear": znear, "zfar": zfar}})
        return len(self.j["cameras"]) - 1

    def image(self, name, png):
        vi = self.view(png)
        self.j.setdefault("images", []).append({"name": name, "bufferView": vi, "mimeType": "image/png"})
        return len(self.j["images"]) - 1

    # -- output --------------------------------------------------------------
    def _binary(self):
        blob = bytearray()
        for bv, data in zip(self.j["bufferViews"], self.view_data):
            blob += b"\x00" * ((-len(blob)) % 4)       # every bufferView 4-byte aligned
            bv["byteOffset"] = len(blob)
            bv["byteLength"] = len(data)
            blob += data
        return bytes(blob)

    def _finish(self):
        for k in ("extensionsUsed",):
            if not self.j[k]:
                del self.j[k]

    def write_glb(self, path):
        blob = self._binary()
        self.j["buffers"] = [{"byteLength": len(blob)}]
        self._finish()
        js = json.dumps(self.j, separators=(",", ":")).encode("utf-8")
        js += b" " * ((-len(js)) % 4)                  # JSON chunk padded with spaces
        bn = blob + b"\x00" * ((-len(blob)) % 4)       # BIN chunk padded with zeros
        total = 12 + 8 + len(js) + 8 + len(bn)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, total))
            f.write(struct.pack("<II", len(js), 0x4E4F534A) + js)
            f.write(struct.pack("<II", len(bn), 0x004E4942) + bn)

    def write_gltf(self, path):
        blob = self._binary()
        bin_name = os.path.splitext(os.path.basename(path))[0] + ".bin"
        self.j["buffers"] = [{"uri": bin_name, "byteLength": len(blob)}]
        self._finish()
        with open(os.path.join(os.path.dirname(path), bin_name), "wb") as f:
            f.write(blob)
        with open(path, "w", encoding="utf-8", newline="\n") as f:
            f.write(json.dumps(self.j, indent=1) + "\n")
