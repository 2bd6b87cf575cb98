#!/usr/bin/env python3
"""Hand-made hostile inputs for import_fuzz_regressions, aimed at places where
tinygltf 2.7 trusts its input (each is rejected with an error by the importer's
pre-validation). Re-run: python3 tests/fuzz/make_regressions.py"""
import json, os, struct, zlib

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "regressions")


def glb(js, bin_chunk=None, bin_len=None, total=None):
    j = json.dumps(js).encode()
    j += b" " * (-len(j) % 4)
    body = struct.pack("<I", len(j)) + b"JSON" + j
    if bin_chunk is not None:
        body += struct.pack("<I", len(bin_chunk) if bin_len is None else bin_len) + b"BIN\0" + bin_chunk
    n = 12 + len(body) if total is None else total
    return b"glTF" + struct.pack("<II", 2, n) + body


def png_header(w, h):
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)) + chunk(b"IEND", b"")


A = {"asset": {"version": "2.0"}}
files = {
    # BIN chunk whose length ends 8 bytes past the file (tinygltf forgets the chunk header).
    "glb_bin_overrun.glb": glb(dict(A, buffers=[{"byteLength": 8}]), b"\0" * 8, bin_len=16, total=None),
    # buffer 0 of byteLength 0 in a .glb (tinygltf calls data.at(0) on an empty vector).
    "glb_zero_length_buffer.glb": glb(dict(A, buffers=[{"byteLength": 0}]), b"\0" * 4),
    # image in a bufferView beyond its buffer.
    "image_view_overrun.glb": glb(dict(A, buffers=[{"byteLength": 4}],
                                       bufferViews=[{"buffer": 0, "byteOffset": 100, "byteLength": 50}],
                                       images=[{"bufferView": 0, "mimeType": "image/png"}]), b"\0" * 4),
    # 100000 x 100000 PNG header: rejected before decoding.
    "image_huge_dimensions.gltf": json.dumps(dict(
        A, images=[{"uri": "data:image/png;base64," + __import__("base64").b64encode(png_header(100000, 100000)).decode()}],
        textures=[{"source": 0}], materials=[{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])).encode(),
    # deeply nested extras (tinygltf converts extras recursively).
    "deep_extras.gltf": (b'{"asset":{"version":"2.0"},"extras":' + b"[" * 2000 + b"]" * 2000 + b"}"),
    # an accessor without bufferView claiming 2^40 elements.
    "huge_zero_accessor.gltf": json.dumps(dict(
        A, accessors=[{"componentType": 5126, "count": 1 << 40, "type": "VEC3"}],
        meshes=[{"primitives": [{"attributes": {"POSITION": 0}}]}], nodes=[{"mesh": 0}])).encode(),
    # node cycle and negative / huge indices.
    "node_cycle.gltf": json.dumps(dict(A, nodes=[{"children": [1]}, {"children": [0]}], scenes=[{"nodes": [0]}])).encode(),
    "bad_indices.gltf": json.dumps(dict(A, nodes=[{"mesh": -5, "children": [4294967295]}], scene=7,
                                        scenes=[{"nodes": [0]}])).encode(),
    # external uri escaping the folder, and an absolute path.
    "uri_escape.gltf": json.dumps(dict(A, buffers=[{"byteLength": 4, "uri": "../../etc/passwd"}],
                                       images=[{"uri": "/etc/passwd"}])).encode(),
}

os.makedirs(OUT, exist_ok=True)
for name, data in files.items():
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(data)
    print(name, len(data))
