"""Reads the parts of a binary glTF (.glb) the add-on needs: the JSON and the
vertex attributes of triangle primitives. No bpy here, so it runs anywhere.

Luxel's write-back is read directly rather than through Blender's glTF
importer: the importer only creates UV layers for TEXCOORD_0..k while every
lower set exists (a lightmap set in TEXCOORD_1 of a mesh without TEXCOORD_0
is dropped), and it renames nodes, meshes and materials that collide with
the user's own, which would break the match back to the user's objects."""

import json
import struct

import numpy as np

_GLB_MAGIC = 0x46546C67  # "glTF"
_CHUNK_JSON = 0x4E4F534A
_CHUNK_BIN = 0x004E4942
_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
           5125: np.uint32, 5126: np.float32}
_NORMALIZE = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}
TRIANGLES = 4


class GlbError(Exception):
    pass


class Glb:
    """One .glb file: ``json`` (the parsed document) and accessor reads."""

    def __init__(self, path):
        with open(path, "rb") as f:
            data = f.read()
        if len(data) < 20 or struct.unpack_from("<I", data, 0)[0] != _GLB_MAGIC:
            raise GlbError(f"{path}: not a binary glTF file")
        self.path = path
        self.json = None
        self.bin = b""
        offset = 12
        while offset + 8 <= len(data):
            length, kind = struct.unpack_from("<II", data, offset)
            chunk = data[offset + 8:offset + 8 + length]
            if kind == _CHUNK_JSON:
                self.json = json.loads(chunk.decode("utf-8"))
            elif kind == _CHUNK_BIN and not self.bin:
                self.bin = chunk
            offset += 8 + length
        if self.json is None:
            raise GlbError(f"{path}: no JSON chunk")

    def accessor(self, index):
        """The accessor as a float32 array (count x components); normalized
        integer UVs are mapped to [0, 1] as glTF says; indices stay integers."""
        acc = self.json["accessors"][index]
        comps = _COMPONENTS[acc["type"]]
        dtype = np.dtype(_DTYPES[acc["componentType"]])
        count = acc["count"]
        if "bufferView" not in acc:  # all zeros (sparse accessors are not written by Luxel)
            return np.zeros((count, comps), dtype=np.float32)
        view = self.json["bufferViews"][acc["bufferView"]]
        if view.get("buffer", 0) != 0:
            raise GlbError(f"{self.path}: accessor {index} is not in the GLB's own buffer")
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        stride = view.get("byteStride", 0) or dtype.itemsize * comps
        rows = np.ndarray((count, comps), dtype=dtype, buffer=self.bin, offset=start,
                          strides=(stride, dtype.itemsize))
        if acc["componentType"] == 5126:
            return np.array(rows, dtype=np.float32)
        if acc.get("normalized"):
            return np.maximum(rows.astype(np.float32) / _NORMALIZE[acc["componentType"]], -1.0)
        return np.array(rows)

    def indices(self, primitive):
        """Triangle corner indices of a primitive (0..n-1 when it has none)."""
        if "indices" in primitive:
            return self.accessor(primitive["indices"]).reshape(-1).astype(np.int64)
        count = self.json["accessors"][primitive["attributes"]["POSITION"]]["count"]
        return np.arange(count, dtype=np.int64)
