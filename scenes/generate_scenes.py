#!/usr/bin/env python3
"""Generate (and check) the bundled Luxel test scenes.

Writes, next to this script:
  cornell_box.gltf + cornell_box.bin   -- .gltf with an external buffer
  foliage_instanced.glb                -- .glb, embedded PNGs, instancing, lights
  procedural_city.glb                  -- 549,574 world triangles (285,442 unique)

Usage (only /usr/bin/python3 with numpy; stdlib otherwise):
  python3 scenes/generate_scenes.py            # generate all scenes, then check them
  python3 scenes/generate_scenes.py --no-check # generate only
  python3 scenes/generate_scenes.py --check    # only parse back + validate + print table

Conventions for every scene (see README.md):
  * glTF 2.0, Y up, metres, right handed; triangle winding is counter-clockwise
    seen from the side the NORMAL points to.
  * every primitive has POSITION/NORMAL/TEXCOORD_0/TEXCOORD_1 (float32); the one
    documented exception is the bench in foliage_instanced.glb (no NORMAL).
  * TEXCOORD_1 is the lightmap UV: each mesh lays out its own charts in the unit
    square with a uniform texel density, >= 2 texels of gutter between chart
    bounding rectangles and a 2 texel border, measured at a 256x256 atlas.
    Charts of one mesh never overlap (instances get their own atlas rect later).

Determinism: all randomness comes from numpy.random.RandomState with fixed seeds
(RandomState's stream is frozen by numpy's compatibility policy), JSON is
emitted in insertion order, PNGs are written with zlib level 9, so re-running
on the same machine reproduces byte-identical files.
"""
import json
import math
import os
import struct
import sys
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))

ATLAS_RES = 256   # reference lightmap resolution the gutter is measured at
GUTTER = 2        # texels between chart rectangles
MARGIN = 2        # texels between charts and the atlas border

# glTF / GL enums
BYTE, UBYTE, SHORT, USHORT, UINT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
NEAREST, LINEAR, LINEAR_MIPMAP_LINEAR = 9728, 9729, 9987
REPEAT, CLAMP_TO_EDGE = 10497, 33071

DTYPE_TO_COMP = {np.dtype(np.float32): FLOAT, np.dtype(np.uint8): UBYTE,
                 np.dtype(np.uint16): USHORT, np.dtype(np.uint32): UINT}
NCOMP_TO_TYPE = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}


# ----------------------------------------------------------------------------
# small math helpers
# ----------------------------------------------------------------------------
def normalize(v):
    v = np.asarray(v, dtype=np.float64)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def quat_axis_angle(axis, angle):
    """Unit quaternion (x, y, z, w) for a rotation of `angle` rad about `axis`."""
    a = normalize(np.array(axis, dtype=np.float64))
    s = math.sin(angle / 2.0)
    return [float(a[0] * s), float(a[1] * s), float(a[2] * s), float(math.cos(angle / 2.0))]


def quat_mul(q1, q2):
    """Hamilton product q1*q2 (apply q2 first, then q1)."""
    x1, y1, z1, w1 = q1
    x2, y2, z2, w2 = q2
    return [w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2]


def quat_from_matrix(m):
    """Rotation matrix (3x3, columns = rotated axes) -> unit quaternion (x,y,z,w)."""
    t = m[0, 0] + m[1, 1] + m[2, 2]
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        q = [0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        q = [(m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s]
    q = np.array(q)
    q /= np.linalg.norm(q)
    return [float(c) for c in q]


def quat_look(eye, target, up=(0.0, 1.0, 0.0)):
    """Rotation that points the node's local -Z (camera/light forward) at target."""
    f = normalize(np.subtract(target, eye))
    r = normalize(np.cross(f, up))
    u = np.cross(r, f)
    return quat_from_matrix(np.stack([r, u, -f], axis=1))


def quat_dir(direction, up=(0.0, 1.0, 0.0)):
    return quat_look((0.0, 0.0, 0.0), direction, up)


def fix_winding(pos, nrm, tris):
    """Flip triangles whose geometric normal disagrees with their vertex normals,
    so that every triangle is CCW seen from the side its normal points to."""
    tris = np.array(tris, dtype=np.int64).reshape(-1, 3)
    a, b, c = pos[tris[:, 0]], pos[tris[:, 1]], pos[tris[:, 2]]
    g = np.cross(b - a, c - a)
    n = nrm[tris].sum(axis=1)
    flip = (g * n).sum(axis=1) < 0
    tris[flip] = tris[flip][:, [0, 2, 1]]
    return tris


def grid_tris(nu, nv):
    """Triangles of an (nu+1) x (nv+1) vertex grid (vertex index = j*(nu+1)+i)."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="xy")
    v0 = (j * (nu + 1) + i).ravel()
    v1, v2, v3 = v0 + 1, v0 + nu + 1, v0 + nu + 2
    return np.concatenate([np.stack([v0, v1, v3], 1), np.stack([v0, v3, v2], 1)])


# ----------------------------------------------------------------------------
# lightmap chart packing (uniform texel density, shelf packer)
# ----------------------------------------------------------------------------
def pack_charts(dims, res=ATLAS_RES, gutter=GUTTER, margin=MARGIN):
    """dims: (n,2) chart extents in metres.  Returns (placements, s) where s is
    the texel density (texels per metre at `res`) and placements[i] = (x, y, rot)
    in texels.  All charts use the same density (largest one that fits)."""
    dims = np.asarray(dims, dtype=np.float64)

    def try_pack(s):
        rects = []
        for i, (w, h) in enumerate(dims):
            W, H = max(1, math.ceil(w * s)), max(1, math.ceil(h * s))
            rot = H > W  # lay every chart "landscape" for the shelf packer
            if rot:
                W, H = H, W
            rects.append((H, W, i, rot))
        rects.sort(key=lambda r: (-r[0], -r[1], r[2]))
        out = [None] * len(dims)
        x = y = margin
        row_h = 0
        for H, W, i, rot in rects:
            if W > res - 2 * margin:
                return None
            if x + W > res - margin:          # start a new shelf
                y += row_h + gutter
                x, row_h = margin, 0
            if y + H > res - margin:
                return None
            out[i] = (x, y, rot)
            x += W + gutter
            row_h = max(row_h, H)
        return out

    hi = (res - 2 * margin) / max(float(dims.max()), 1e-9)
    r = try_pack(hi)
    if r is not None:
        return r, hi
    lo, best = 0.0, None
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        r = try_pack(mid)
        if r is None:
            hi = mid
        else:
            lo, best = mid, (r, mid)
    assert best is not None
    return best


class MeshBuilder:
    """Collects charts (connected pieces of surface with a flat 2D parameterisation
    in metres) and produces glTF primitives (one per material) with packed
    lightmap UVs."""

    def __init__(self):
        self.charts = []

    def add_chart(self, material, pos, nrm, uv0, param, tris, orient_nrm=None):
        pos = np.asarray(pos, np.float64)
        nrm = normalize(nrm)
        tris = fix_winding(pos, nrm if orient_nrm is None else orient_nrm, tris)
        self.charts.append(dict(material=material, pos=pos, nrm=nrm,
                                uv0=np.asarray(uv0, np.float64),
                                param=np.asarray(param, np.float64), tris=tris))

    def quad(self, material, p4, normal_hint, uv0=None):
        """One planar(ish) quad = one chart.  Vertex order is fixed up so the
        Newell normal points along normal_hint."""
        p4 = np.asarray(p4, np.float64)
        n = np.zeros(3)
        for k in range(4):  # Newell normal (robust for slightly non-planar quads)
            a, b = p4[k], p4[(k + 1) % 4]
            n += [(a[1] - b[1]) * (a[2] + b[2]), (a[2] - b[2]) * (a[0] + b[0]), (a[0] - b[0]) * (a[1] + b[1])]
        n = normalize(n)
        if np.dot(n, normal_hint) < 0:
            p4, n = p4[::-1].copy(), -n
        e0 = normalize(p4[1] - p4[0])
        e1 = np.cross(n, e0)
        param = np.stack([(p4 - p4[0]) @ e0, (p4 - p4[0]) @ e1], axis=1)
        self.add_chart(material, p4, np.tile(n, (4, 1)),
                       param if uv0 is None else uv0, param, [[0, 1, 2], [0, 2, 3]])

    def grid(self, material, origin, du, dv, nu, nv, normal, uv0_scale=1.0):
        """Planar parallelogram origin + s*du + t*dv, tessellated nu x nv; one chart."""
        s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="xy")
        s, t = s.ravel(), t.ravel()
        du, dv = np.asarray(du, np.float64), np.asarray(dv, np.float64)
        pos = np.asarray(origin, np.float64)[None] + s[:, None] * du + t[:, None] * dv
        param = np.stack([s * np.linalg.norm(du), t * np.linalg.norm(dv)], axis=1)
        self.add_chart(material, pos, np.tile(normal, (len(pos), 1)), param * uv0_scale,
                       param, grid_tris(nu, nv))

    def box(self, material, center, size, skip=()):
        """Axis-aligned box, 6 quad charts with outward normals ('-y' etc. in skip
        omits faces)."""
        c, h = np.asarray(center, np.float64), 0.5 * np.asarray(size, np.float64)
        for axis in range(3):
            for sgn in (1, -1):
                if ("+" if sgn > 0 else "-") + "xyz"[axis] in skip:
                    continue
                u, v = (axis + 1) % 3, (axis + 2) % 3
                p = []
                for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                    q = c.copy()
                    q[axis] += sgn * h[axis]
                    q[u] += a * h[u]
                    q[v] += b * h[v]
                    p.append(q)
                n = np.zeros(3)
                n[axis] = sgn
                self.quad(material, p, n)

    def build(self):
        """Pack charts; returns list of primitives
        {material, pos, nrm, uv0, uv1, idx} (float32 / int64 indices)."""
        mins = [c["param"].min(axis=0) for c in self.charts]
        dims = [c["param"].max(axis=0) - m for c, m in zip(self.charts, mins)]
        placements, s = pack_charts(dims)
        by_mat = {}
        for c, m, (x, y, rot) in zip(self.charts, mins, placements):
            p = (c["param"] - m) * s
            if rot:
                p = p[:, ::-1]
            uv1 = (p + np.array([x, y], np.float64)) / ATLAS_RES
            by_mat.setdefault(c["material"], []).append((c, uv1))
        prims = []
        for mat, lst in by_mat.items():
            base, idx = 0, []
            for c, _ in lst:
                idx.append(c["tris"] + base)
                base += len(c["pos"])
            cat = lambda key: np.concatenate([c[key] for c, _ in lst]).astype(np.float32)
            prims.append(dict(material=mat, pos=cat("pos"), nrm=cat("nrm"), uv0=cat("uv0"),
                              uv1=np.concatenate([u for _, u in lst]).astype(np.float32),
                              idx=np.concatenate(idx)))
        return prims


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


# ============================================================================
# 1. Cornell box
# ============================================================================
# Geometry from the Cornell box data page (https://www.graphics.cornell.edu/online/box/data.html).
# The data is given in "units" = mm of the real 0.556 m box; we scale it by 0.01
# so the box is 5.56 m wide (the scale of the Capsaicin / pablode glTF versions).
# Mapping data (x, y, z) -> glTF (2.78 - 0.01 x, 0.01 y, -0.01 z): a 180 degree
# rotation about Y (keeps handedness and winding) so the original camera
# (278, 273, -800) looking +z becomes (0, 2.73, 8) looking -z, the glTF camera
# default.  Red wall ends up at x = -2.78 (left in the camera view), green at +2.78.
CORNELL = {
    "floor": ([552.8, 0, 0, 0, 0, 0, 0, 0, 559.2, 549.6, 0, 559.2], "white"),
    "ceiling": ([556, 548.8, 0, 556, 548.8, 559.2, 0, 548.8, 559.2, 0, 548.8, 0], "white"),
    "back_wall": ([549.6, 0, 559.2, 0, 0, 559.2, 0, 548.8, 559.2, 556, 548.8, 559.2], "white"),
    "right_wall": ([0, 0, 559.2, 0, 0, 0, 0, 548.8, 0, 0, 548.8, 559.2], "green"),
    "left_wall": ([552.8, 0, 0, 549.6, 0, 559.2, 556, 548.8, 559.2, 556, 548.8, 0], "red"),
}
SHORT_BLOCK = [
    [130, 165, 65, 82, 165, 225, 240, 165, 272, 290, 165, 114],
    [290, 0, 114, 290, 165, 114, 240, 165, 272, 240, 0, 272],
    [130, 0, 65, 130, 165, 65, 290, 165, 114, 290, 0, 114],
    [82, 0, 225, 82, 165, 225, 130, 165, 65, 130, 0, 65],
    [240, 0, 272, 240, 165, 272, 82, 165, 225, 82, 0, 225]]
TALL_BLOCK = [
    [423, 330, 247, 265, 330, 296, 314, 330, 456, 472, 330, 406],
    [423, 0, 247, 423, 330, 247, 472, 330, 406, 472, 0, 406],
    [472, 0, 406, 472, 330, 406, 314, 330, 456, 314, 0, 456],
    [314, 0, 456, 314, 330, 456, 265, 330, 296, 265, 0, 296],
    [265, 0, 296, 265, 330, 296, 423, 330, 247, 423, 0, 247]]
# Data-page light is at y = 548.8 (coplanar with the ceiling); we lower it by
# 1 cm (glTF units) to avoid coplanar surfaces.
LIGHT = [343, 547.8, 227, 343, 547.8, 332, 213, 547.8, 332, 213, 547.8, 227]


def cornell_xform(flat):
    p = np.asarray(flat, np.float64).reshape(-1, 3)
    return np.stack([2.78 - 0.01 * p[:, 0], 0.01 * p[:, 1], -0.01 * p[:, 2]], axis=1) + 0.0  # no -0.0


def make_cornell_box(path):
    w = GltfWriter("CornellBox")
    lambert = dict(metallic=0.0, roughness=1.0, doubleSided=False)
    mats = {"white": w.material("White", [0.725, 0.71, 0.68, 1.0], **lambert),
            "red": w.material("Red", [0.63, 0.065, 0.05, 1.0], **lambert),
            "green": w.material("Green", [0.14, 0.45, 0.091, 1.0], **lambert),
            "light": w.material("Light", [0.78, 0.78, 0.78, 1.0], **lambert,
                                emissiveFactor=[1.0, 0.706, 0.235],
                                extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 17.0}})}
    w.j["extensionsUsed"].append("KHR_materials_emissive_strength")

    mb = MeshBuilder()
    room_center = np.array([0.0, 2.744, -2.796])
    for name, (flat, mat) in CORNELL.items():       # room faces point inward
        p = cornell_xform(flat)
        mb.quad(mats[mat], p, room_center - p.mean(axis=0))
    for block in (SHORT_BLOCK, TALL_BLOCK):           # block faces point outward
        quads = [cornell_xform(q) for q in block]
        c = np.concatenate(quads).mean(axis=0)
        c[1] = quads[0][:, 1].max() / 2               # centroid height = half block height
        for p in quads:
            mb.quad(mats["white"], p, p.mean(axis=0) - c)
    mb.quad(mats["light"], cornell_xform(LIGHT), [0.0, -1.0, 0.0])  # emits downward

    mesh = w.mesh("CornellBox", mb.build(), interleave=True)      # interleaved, byteStride 40
    w.node("CornellBox", mesh=mesh)
    cam = w.camera("CornellCamera", 2.0 * math.atan(0.0125 / 0.035), 1.0, 0.1, 100.0)
    w.node("Camera", camera=cam, translation=[0.0, 2.73, 8.0])
    w.write_gltf(path)


# ============================================================================
# 2. Foliage with instancing, alpha-tested cards, textures, punctual lights
# ============================================================================
def checker_texture():
    """128x128 RGB checker, 16 px squares (8x8 per tile), sRGB values."""
    y, x = np.mgrid[0:128, 0:128]
    odd = ((x // 16) + (y // 16)) % 2 == 1
    img = np.empty((128, 128, 3), np.uint8)
    img[...] = (186, 178, 150)
    img[odd] = (104, 122, 82)
    return img


def leaf_texture(seed=7):
    """256x256 RGBA: a fan of pointed leaves on a stem; alpha 255 inside leaves /
    stems, 0 elsewhere (RGB outside is the mean leaf green so bilinear filtering
    does not bleed dark fringes)."""
    rs = np.random.RandomState(seed)
    N = 256
    yy, xx = np.mgrid[0:N, 0:N].astype(np.float64) + 0.5
    rgb = np.zeros((N, N, 3))
    rgb[...] = (60, 110, 40)
    alpha = np.zeros((N, N), bool)
    root = np.array([128.0, 250.0])
    # stems + leaves: (angle from vertical in degrees, stem length, leaf length, leaf width)
    leaves = [(-62, 40, 92, 40), (-35, 70, 104, 44), (-10, 95, 112, 46), (12, 88, 108, 44),
              (38, 66, 100, 42), (64, 38, 90, 38), (0, 20, 70, 34)]
    for ang, stem, length, width in leaves:
        a = math.radians(ang + rs.uniform(-4, 4))
        d = np.array([math.sin(a), -math.cos(a)])              # image y grows downward
        base = root + d * stem
        # stem: thick line root -> base
        t = np.clip(((xx - root[0]) * d[0] + (yy - root[1]) * d[1]) / stem, 0, 1)
        dist = np.hypot(xx - (root[0] + t * d[0] * stem), yy - (root[1] + t * d[1] * stem))
        stem_m = dist < 2.2
        rgb[stem_m] = (70, 95, 35)
        alpha |= stem_m
        # leaf: pointed lens |t| < w/2 * sin(pi s / L)^0.8 along direction d
        s = (xx - base[0]) * d[0] + (yy - base[1]) * d[1]
        q = -(xx - base[0]) * d[1] + (yy - base[1]) * d[0]
        inside = (s > 0) & (s < length)
        half = 0.5 * width * np.sin(np.pi * np.clip(s / length, 0, 1)) ** 0.8
        leaf_m = inside & (np.abs(q) < half)
        g = rs.uniform(0.8, 1.15)
        shade = (0.75 + 0.35 * (s / length))[..., None] * np.array([52, 128, 38]) * g
        vein = (np.abs(q) < 1.3) | ((np.abs(np.abs(q) - 0.55 * (s % 18)) < 0.9) & (np.abs(q) < half * 0.8))
        col = np.where(vein[..., None], shade * 1.35, shade)
        rgb[leaf_m] = col[leaf_m]
        alpha |= leaf_m
    rgb += rs.uniform(-6, 6, size=rgb.shape)                   # a little grain
    img = np.empty((N, N, 4), np.uint8)
    img[..., :3] = np.clip(np.rint(rgb), 0, 255).astype(np.uint8)
    img[..., 3] = np.where(alpha, 255, 0).astype(np.uint8)
    return img


def plant_mesh(material):
    """5 alpha-tested cards: 3 vertical 0.9 x 0.9 m cards crossed at 60 degrees
    plus 2 lower cards tilted 50 degrees outward.  Each card is one chart."""
    mb = MeshBuilder()
    cards = [(0.0, 0.0, 0.9, 0.9, 0.0), (60.0, 0.0, 0.9, 0.9, 0.0), (120.0, 0.0, 0.9, 0.9, 0.0),
             (30.0, 50.0, 0.7, 0.55, 0.12), (210.0, 50.0, 0.7, 0.55, 0.12)]
    for yaw, tilt, wdt, hgt, out in cards:
        local = np.array([[-wdt / 2, 0, 0], [wdt / 2, 0, 0], [wdt / 2, hgt, 0], [-wdt / 2, hgt, 0]])
        n = np.array([0.0, 0.0, 1.0])
        ct, st = math.cos(math.radians(tilt)), math.sin(math.radians(tilt))
        rx = np.array([[1, 0, 0], [0, ct, -st], [0, st, ct]])   # top leans toward +z
        cy, sy = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
        ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        R = ry @ rx
        p = local @ R.T + R @ np.array([0.0, 0.03, out])
        nn = R @ n
        uv0 = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float64)  # v=0 is the image top
        param = np.array([[0, 0], [wdt, 0], [wdt, hgt], [0, hgt]], np.float64)
        mb.add_chart(material, p, np.tile(nn, (4, 1)), uv0, param, [[0, 1, 2], [0, 2, 3]])
    return mb.build()


def make_foliage(path):
    rs = np.random.RandomState(1234)
    w = GltfWriter("FoliageInstanced")
    j = w.j
    j["samplers"] = [{"name": "RepeatMipmapped", "magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR,
                      "wrapS": REPEAT, "wrapT": REPEAT},
                     {"name": "ClampLinear", "magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR,
                      "wrapS": CLAMP_TO_EDGE, "wrapT": CLAMP_TO_EDGE}]
    img_checker = w.image("GroundChecker", png_bytes(checker_texture()))
    img_leaf = w.image("LeafRGBA", png_bytes(leaf_texture()))
    j["textures"] = [{"name": "GroundChecker", "sampler": 0, "source": img_checker},
                     {"name": "Leaf", "sampler": 1, "source": img_leaf}]
    m_ground = w.material("Ground", [1, 1, 1, 1], 0.0, 0.95, base_texture=0)
    m_stone = w.material("Stone", [0.50, 0.48, 0.45, 1], 0.0, 0.9)
    m_bench = w.material("BenchStone", [0.62, 0.60, 0.56, 1], 0.0, 0.8)
    m_leaf = w.material("Leaves", [1, 1, 1, 1], 0.0, 0.8, base_texture=1,
                        alphaMode="MASK", alphaCutoff=0.5, doubleSided=True)

    # ground: 20 x 20 m, 10 x 10 cells; TEXCOORD_0 = world xz / 2 m (checker tile repeats every 2 m)
    mb = MeshBuilder()
    mb.grid(m_ground, [-10, 0, -10], [20, 0, 0], [0, 0, 20], 10, 10, [0, 1, 0], uv0_scale=0.5)
    mesh_ground = w.mesh("Ground", mb.build())

    # low stone wall: body + overhanging cap (bottom faces omitted: they sit on the ground)
    mb = MeshBuilder()
    mb.box(m_stone, [0, 0.4, 0], [4.0, 0.8, 0.3], skip=("-y",))
    mb.box(m_stone, [0, 0.85, 0], [4.2, 0.1, 0.4])
    mesh_wall = w.mesh("StoneWall", mb.build())

    # bench: seat slab + two legs; THIS primitive has no NORMAL (normal generation test)
    mb = MeshBuilder()
    mb.box(m_bench, [0, 0.45, 0], [1.6, 0.08, 0.45])
    mb.box(m_bench, [-0.65, 0.205, 0], [0.08, 0.41, 0.4], skip=("-y", "+y"))
    mb.box(m_bench, [0.65, 0.205, 0], [0.08, 0.41, 0.4], skip=("-y", "+y"))
    mesh_bench = w.mesh("Bench_NoNormals", mb.build(), drop_normals=True)

    # the instanced plant: stored once, u8 indices
    mesh_plant = w.mesh("PlantCards", plant_mesh(m_leaf), index_dtype=np.uint8)

    w.node("Ground", mesh=mesh_ground)
    w.node("StoneWall", mesh=mesh_wall, translation=[0.0, 0.0, -5.0])
    w.node("Bench", mesh=mesh_bench, translation=[2.0, 0.0, 0.5],
           rotation=quat_axis_angle([0, 1, 0], math.radians(20)))

    def plant_trs():
        yaw = quat_axis_angle([0, 1, 0], rs.uniform(0, 2 * math.pi))
        lean = quat_axis_angle([1, 0, rs.uniform(-1, 1)], math.radians(rs.uniform(-8, 8)))
        s = rs.uniform(0.7, 1.3)
        return quat_mul(yaw, lean), [s * rs.uniform(0.85, 1.15), s * rs.uniform(0.8, 1.4), s * rs.uniform(0.85, 1.15)]

    # 26 plants directly under the scene root (avoid bench / wall / group area)
    placed = 0
    while placed < 26:
        x, z = rs.uniform(-9, 9), rs.uniform(-9, 9)
        if (abs(x - 2.0) < 1.3 and abs(z - 0.5) < 0.9) or (abs(z + 5.0) < 0.8 and abs(x) < 2.6) \
                or (abs(x + 4.0) < 3.0 and abs(z - 3.0) < 3.0):
            continue
        rot, scl = plant_trs()
        w.node("Plant_%02d" % placed, mesh=mesh_plant, translation=[x, 0.0, z], rotation=rot, scale=scl)
        placed += 1
    # 10 plants under a transformed group, 4 more under a nested group given as a matrix
    group = w.node("PlantGroup", translation=[-4.0, 0.0, 3.0],
                   rotation=quat_axis_angle([0, 1, 0], math.radians(35)), scale=[1.25, 1.25, 1.25])
    for k in range(10):
        a = 2 * math.pi * k / 10
        rot, scl = plant_trs()
        w.node("GroupPlant_%02d" % k, parent=group, mesh=mesh_plant,
               translation=[1.6 * math.cos(a), 0.0, 1.6 * math.sin(a)], rotation=rot, scale=scl)
    c, s, sc = math.cos(math.radians(90)), math.sin(math.radians(90)), 0.8
    sub = w.node("PlantSubGroup", parent=group,   # column-major: rotY(90) * scale(0.8), then translate
                 matrix=[sc * c, 0.0, -sc * s, 0.0, 0.0, sc, 0.0, 0.0, sc * s, 0.0, sc * c, 0.0, 0.3, 0.0, -0.2, 1.0])
    for k in range(4):
        rot, scl = plant_trs()
        w.node("SubGroupPlant_%02d" % k, parent=sub, mesh=mesh_plant,
               translation=[0.45 * (k - 1.5), 0.0, 0.25 * (k % 2)], rotation=rot, scale=scl)

    # KHR_lights_punctual: sun (lux), point + spot (candela)
    j["extensionsUsed"].append("KHR_lights_punctual")
    j.setdefault("extensions", {})["KHR_lights_punctual"] = {"lights": [
        {"name": "Sun", "type": "directional", "color": [1.0, 0.96, 0.9], "intensity": 3.0},
        {"name": "Lantern", "type": "point", "color": [1.0, 0.75, 0.45], "intensity": 40.0, "range": 12.0},
        {"name": "BenchSpot", "type": "spot", "color": [0.9, 0.95, 1.0], "intensity": 150.0,
         "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}}]}
    w.node("Sun", rotation=quat_dir([-0.4, -0.8, -0.45]), extensions={"KHR_lights_punctual": {"light": 0}})
    w.node("Lantern", translation=[-3.0, 1.2, 2.0], extensions={"KHR_lights_punctual": {"light": 1}})
    w.node("BenchSpot", translation=[2.0, 3.0, 1.5],
           rotation=quat_look([2.0, 3.0, 1.5], [2.0, 0.4, 0.5]), extensions={"KHR_lights_punctual": {"light": 2}})
    cam = w.camera("FoliageCamera", 0.9, 16.0 / 9.0, 0.05, 200.0)
    w.node("Camera", camera=cam, translation=[0.0, 2.2, 10.0], rotation=quat_look([0, 2.2, 10], [0, 0.5, 0]))
    w.write_glb(path)


# ============================================================================
# 3. Procedural city
# ============================================================================
class ValueNoise:
    """Smooth 2D value noise on a periodic random lattice (RandomState seeded)."""

    def __init__(self, seed, n=64):
        self.g = np.random.RandomState(seed).rand(n, n)
        self.n = n

    def __call__(self, x, z):
        x, z = np.asarray(x, np.float64), np.asarray(z, np.float64)
        xi, zi = np.floor(x).astype(np.int64), np.floor(z).astype(np.int64)
        fx, fz = x - xi, z - zi
        sx, sz = fx * fx * (3 - 2 * fx), fz * fz * (3 - 2 * fz)
        g, n = self.g, self.n
        a, b = g[xi % n, zi % n], g[(xi + 1) % n, zi % n]
        c, d = g[xi % n, (zi + 1) % n], g[(xi + 1) % n, (zi + 1) % n]
        return (a * (1 - sx) + b * sx) * (1 - sz) + (c * (1 - sx) + d * sx) * sz


NOISE = [ValueNoise(11), ValueNoise(12), ValueNoise(13)]
TERRAIN_SIZE, TERRAIN_CELLS = 640.0, 320   # 2 m cells, 204,800 triangles
CITY_HALF = 200.0


def terrain_height(x, z):
    h = (7.0 * (NOISE[0](x / 110.0 + 3.3, z / 110.0 + 7.1) - 0.5)
         + 2.0 * (NOISE[1](x / 37.0, z / 37.0) - 0.5)
         + 0.4 * (NOISE[2](x / 9.0, z / 9.0) - 0.5))
    cheb = np.maximum(np.abs(x), np.abs(z))
    t = np.clip((cheb - 190.0) / 90.0, 0, 1)
    return h * (0.25 + 0.75 * t * t * (3 - 2 * t))   # flatter inside the city


def terrain_mesh(material):
    n = TERRAIN_CELLS
    lin = np.linspace(-TERRAIN_SIZE / 2, TERRAIN_SIZE / 2, n + 1)
    X, Z = np.meshgrid(lin, lin, indexing="xy")          # vertex index = j*(n+1)+i, x along i
    H = terrain_height(X, Z)
    # analytic-ish normals from central differences of the height function
    e = 0.5
    dhdx = (terrain_height(X + e, Z) - terrain_height(X - e, Z)) / (2 * e)
    dhdz = (terrain_height(X, Z + e) - terrain_height(X, Z - e)) / (2 * e)
    nrm = normalize(np.stack([-dhdx, np.ones_like(H), -dhdz], axis=-1).reshape(-1, 3))
    pos = np.stack([X, H, Z], axis=-1).reshape(-1, 3)
    tris = fix_winding(pos, nrm, grid_tris(n, n))
    b = MARGIN / ATLAS_RES                                 # whole unit square minus border
    uv1 = b + (1 - 2 * b) * (pos[:, [0, 2]] + TERRAIN_SIZE / 2) / TERRAIN_SIZE
    return [dict(material=material, pos=pos.astype(np.float32), nrm=nrm.astype(np.float32),
                 uv0=(pos[:, [0, 2]] / 8.0).astype(np.float32), uv1=uv1.astype(np.float32), idx=tris)]


def building_mesh(rs, w, d, height, tiers, wall_mats, roof_mat):
    """Stacked set-back boxes; every wall is a grid chart (3 m floors x ~2.5 m window bays),
    roofs are quads (the exposed roof ring of a lower tier is split into 4 quads)."""
    mb = MeshBuilder()
    x0, x1, z0, z1 = -w / 2, w / 2, -d / 2, d / 2
    cuts = np.sort(rs.uniform(0.35, 0.85, size=tiers - 1))[::-1] if tiers > 1 else []
    levels = [0.0] + [height * (1 - c) for c in cuts] + [height]
    levels = sorted(levels)
    for t in range(len(levels) - 1):
        ya, yb = levels[t], levels[t + 1]
        mat = wall_mats[t]
        nv = max(1, int(round((yb - ya) / 3.0)))
        for (ax, az), (bx, bz), n in (((x0, z1), (x1, z1), (0, 0, 1)), ((x1, z1), (x1, z0), (1, 0, 0)),
                                      ((x1, z0), (x0, z0), (0, 0, -1)), ((x0, z0), (x0, z1), (-1, 0, 0))):
            length = math.hypot(bx - ax, bz - az)
            mb.grid(mat, [ax, ya, az], [bx - ax, 0, bz - az], [0, yb - ya, 0],
                    max(1, int(round(length / 2.5))), nv, n)
        last = t == len(levels) - 2
        if last:
            mb.quad(roof_mat, [[x0, yb, z0], [x1, yb, z0], [x1, yb, z1], [x0, yb, z1]], [0, 1, 0])
        else:
            # next tier footprint, inset by a random setback on each side
            ins = [rs.uniform(1.5, max(1.6, 0.22 * (x1 - x0))), rs.uniform(1.5, max(1.6, 0.22 * (x1 - x0))),
                   rs.uniform(1.5, max(1.6, 0.22 * (z1 - z0))), rs.uniform(1.5, max(1.6, 0.22 * (z1 - z0)))]
            nx0, nx1, nz0, nz1 = x0 + ins[0], x1 - ins[1], z0 + ins[2], z1 - ins[3]
            ring = [[x0, x1, z0, nz0], [x0, x1, nz1, z1], [x0, nx0, nz0, nz1], [nx1, x1, nz0, nz1]]
            for a0, a1, b0, b1 in ring:
                mb.quad(roof_mat, [[a0, yb, b0], [a1, yb, b0], [a1, yb, b1], [a0, yb, b1]], [0, 1, 0])
            x0, x1, z0, z1 = nx0, nx1, nz0, nz1
    return mb.build()


def cylinder_chart(mb, mat, r, y0, y1, S, R):
    th = np.linspace(0, 2 * np.pi, S + 1)               # seam duplicated (i = 0 and i = S)
    ys = np.linspace(y0, y1, R + 1)
    T, Y = np.meshgrid(th, ys, indexing="xy")
    T, Y = T.ravel(), Y.ravel()
    pos = np.stack([r * np.cos(T), Y, r * np.sin(T)], 1)
    nrm = np.stack([np.cos(T), np.zeros_like(T), np.sin(T)], 1)
    mb.add_chart(mat, pos, nrm, np.stack([T / (2 * np.pi), Y], 1), np.stack([r * T, Y], 1), grid_tris(S, R))


def cone_chart(mb, mat, r, yb, h, S, R):
    """Cone side unrolled exactly (a developable surface): sector of radius L and
    angle 2*pi*r/L.  Apex fan uses one apex vertex per segment."""
    L = math.hypot(r, h)
    k = r / L
    pos, nrm, par, tris = [], [], [], []

    def cone_n(theta):
        return normalize(np.array([h * math.cos(theta), r, h * math.sin(theta)]))

    th = np.linspace(0, 2 * np.pi, S + 1)
    for i in range(S):                                  # apex vertices
        tm = 0.5 * (th[i] + th[i + 1])
        pos.append([0, yb + h, 0]); nrm.append(cone_n(tm)); par.append([0, 0])
    ring0 = len(pos)
    for jr in range(1, R + 1):                          # rings 1..R (t = jr/R)
        t = jr / R
        for i in range(S + 1):
            pos.append([t * r * math.cos(th[i]), yb + h * (1 - t), t * r * math.sin(th[i])])
            nrm.append(cone_n(th[i]))
            par.append([t * L * math.cos(th[i] * k), t * L * math.sin(th[i] * k)])
    ring = lambda jr, i: ring0 + (jr - 1) * (S + 1) + i
    for i in range(S):
        tris.append([i, ring(1, i), ring(1, i + 1)])
    for jr in range(1, R):
        for i in range(S):
            a, b, c, d = ring(jr, i), ring(jr, i + 1), ring(jr + 1, i), ring(jr + 1, i + 1)
            tris += [[a, c, d], [a, d, b]]
    pos, par = np.array(pos), np.array(par)
    mb.add_chart(mat, pos, np.array(nrm), par, par, tris)


def disk_chart(mb, mat, r, y, S, R, normal_y=-1.0):
    pos, tris = [[0, y, 0]], []
    th = np.linspace(0, 2 * np.pi, S, endpoint=False)
    for jr in range(1, R + 1):
        for i in range(S):
            pos.append([r * jr / R * math.cos(th[i]), y, r * jr / R * math.sin(th[i])])
    ring = lambda jr, i: 1 + (jr - 1) * S + (i % S)
    for i in range(S):
        tris.append([0, ring(1, i), ring(1, i + 1)])
    for jr in range(1, R):
        for i in range(S):
            tris += [[ring(jr, i), ring(jr + 1, i), ring(jr + 1, i + 1)], [ring(jr, i), ring(jr + 1, i + 1), ring(jr, i + 1)]]
    pos = np.array(pos)
    mb.add_chart(mat, pos, np.tile([0, normal_y, 0], (len(pos), 1)), pos[:, [0, 2]], pos[:, [0, 2]], tris)


def tree_mesh(bark, leaves):
    """Conifer: trunk cylinder (12 x 4) + 3 stacked cones (20 x 6) with underside
    disks (20 x 3): 96 + 3*220 + 3*100 = 1056 triangles."""
    mb = MeshBuilder()
    cylinder_chart(mb, bark, 0.22, -0.3, 1.9, 12, 4)
    for yb, r, h in ((1.4, 1.6, 2.6), (2.6, 1.25, 2.3), (3.7, 0.9, 2.0)):
        cone_chart(mb, leaves, r, yb, h, 20, 6)
        disk_chart(mb, leaves, r, yb, 20, 3)
    return mb.build()


def rock_mesh(mat, seed=99, N=9):
    """Displaced cube-sphere: 6 faces x 9 x 9 quads = 972 triangles.  One chart per
    cube face; smooth normals welded across the face seams."""
    rs = np.random.RandomState(seed)
    freqs = rs.normal(size=(6, 3)) * 2.2
    phases = rs.uniform(0, 2 * np.pi, 6)
    amps = rs.uniform(0.04, 0.09, 6)
    lin = np.linspace(-1, 1, N + 1)
    A, B = np.meshgrid(lin, lin, indexing="xy")
    A, B = A.ravel(), B.ravel()
    faces = []
    for axis in range(3):
        for sgn in (1.0, -1.0):
            u, v = np.zeros(3), np.zeros(3)
            u[(axis + 1) % 3], v[(axis + 2) % 3] = 1.0, 1.0
            nax = np.zeros(3)
            nax[axis] = sgn
            cube = nax[None] + A[:, None] * u + B[:, None] * v
            dirs = normalize(cube)
            r = 1.0 + (amps[None] * np.sin(dirs @ freqs.T + phases[None])).sum(1)
            pos = dirs * r[:, None] * np.array([1.0, 0.62, 0.85])
            tris = fix_winding(pos, dirs, grid_tris(N, N))  # outward, using radial direction
            faces.append((pos, tris))
    # smooth normals: accumulate area-weighted face normals on welded positions
    allp = np.concatenate([p for p, _ in faces])
    key = np.round(allp * 1e5).astype(np.int64)
    _, weld = np.unique(key, axis=0, return_inverse=True)
    weld = weld.reshape(-1)
    acc = np.zeros((weld.max() + 1, 3))
    base = 0
    for p, t in faces:
        fn = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
        for c in range(3):
            np.add.at(acc, weld[base + t[:, c]], fn)
        base += len(p)
    nrm_all = normalize(acc)[weld]
    mb, base = MeshBuilder(), 0
    for p, t in faces:
        tri_area = 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), axis=1).sum()
        scale = math.sqrt(tri_area / 4.0)                 # face param square has area 4
        param = np.stack([A, B], 1) * scale
        n = nrm_all[base:base + len(p)]
        mb.add_chart(mat, p, n, param, param, t, orient_nrm=normalize(p))
        base += len(p)
    return mb.build()


def make_city(path):
    rs = np.random.RandomState(2024)
    w = GltfWriter("ProceduralCity")
    m_terrain = w.material("Terrain", [0.33, 0.38, 0.24, 1], 0.0, 1.0)
    m_concrete = w.material("Concrete", [0.58, 0.57, 0.54, 1], 0.0, 0.9)
    m_glass = w.material("DarkGlass", [0.05, 0.06, 0.07, 1], 0.0, 0.15)
    m_roof = w.material("Roof", [0.30, 0.30, 0.32, 1], 0.0, 0.95)
    m_bark = w.material("Bark", [0.33, 0.24, 0.16, 1], 0.0, 1.0)
    m_needles = w.material("Needles", [0.12, 0.30, 0.11, 1], 0.0, 0.9)
    m_rock = w.material("Rock", [0.45, 0.43, 0.40, 1], 0.0, 0.95)

    mesh_terrain = w.mesh("Terrain", terrain_mesh(m_terrain), index_dtype=np.uint32)
    w.node("Terrain", mesh=mesh_terrain)

    # --- buildings: 8 x 8 blocks of 38 m with 12 m streets, two blocks are parks
    parks = {(2, 5), (5, 2)}
    bld_root = w.node("Buildings")
    nb = 0
    for bi in range(8):
        for bj in range(8):
            if (bi, bj) in parks:
                continue
            bx0, bz0 = -CITY_HALF + 50 * bi + 6, -CITY_HALF + 50 * bj + 6
            split = int(rs.choice(3, p=[0.2, 0.35, 0.45]))
            nx, nz = [(1, 1), (2, 1), (2, 2)][split]
            for li in range(nx):
                for lj in range(nz):
                    lx0, lx1 = bx0 + 38.0 * li / nx, bx0 + 38.0 * (li + 1) / nx
                    lz0, lz1 = bz0 + 38.0 * lj / nz, bz0 + 38.0 * (lj + 1) / nz
                    fx0, fx1 = lx0 + rs.uniform(1.5, 3.5), lx1 - rs.uniform(1.5, 3.5)
                    fz0, fz1 = lz0 + rs.uniform(1.5, 3.5), lz1 - rs.uniform(1.5, 3.5)
                    cx, cz, fw, fd = 0.5 * (fx0 + fx1), 0.5 * (fz0 + fz1), fx1 - fx0, fz1 - fz0
                    r = math.hypot(cx, cz)
                    height = max(6.0, (8 + 70 * math.exp(-(r / 120.0) ** 2)) * rs.uniform(0.5, 1.4) + rs.uniform(0, 8))
                    tiers = 1 if height < 20 or min(fw, fd) < 12 else rs.randint(1, 4)
                    walls = [m_glass if rs.rand() < 0.3 else m_concrete for _ in range(tiers)]
                    yaw = rs.randint(4)                       # node yaw k*90 deg
                    lw, ld = (fd, fw) if yaw % 2 else (fw, fd)
                    prims = building_mesh(rs, lw, ld, height, tiers, walls, m_roof)
                    sx, sz = np.meshgrid(np.linspace(fx0 - 2, fx1 + 2, 7), np.linspace(fz0 - 2, fz1 + 2, 7))
                    base_y = float(terrain_height(sx, sz).min()) - 0.6  # sink below the terrain
                    mesh = w.mesh("Building_%03d" % nb, prims, shared=True)
                    w.node("Building_%03d" % nb, parent=bld_root, mesh=mesh, translation=[cx, base_y, cz],
                           rotation=quat_axis_angle([0, 1, 0], yaw * math.pi / 2))
                    nb += 1

    # --- instanced vegetation / rocks, placed in the outskirts and the two parks
    mesh_tree = w.mesh("Tree", tree_mesh(m_bark, m_needles), shared=True)
    mesh_rock = w.mesh("Rock", rock_mesh(m_rock), shared=True)
    taken = []

    def sample_spot(min_d):
        while True:
            if rs.rand() < 0.2:                            # park block
                bi, bj = sorted(parks)[rs.randint(len(parks))]
                x = -CITY_HALF + 50 * bi + rs.uniform(9, 41)
                z = -CITY_HALF + 50 * bj + rs.uniform(9, 41)
            else:                                          # outskirts ring
                x, z = rs.uniform(-310, 310), rs.uniform(-310, 310)
                if max(abs(x), abs(z)) < CITY_HALF + 10:
                    continue
            if all((x - a) ** 2 + (z - b) ** 2 > min_d ** 2 for a, b in taken):
                taken.append((x, z))
                return x, z

    tree_root = w.node("Trees")
    for k in range(160):
        x, z = sample_spot(5.0)
        s = rs.uniform(0.8, 1.5)
        w.node("Tree_%03d" % k, parent=tree_root, mesh=mesh_tree,
               translation=[x, float(terrain_height(x, z)), z],
               rotation=quat_axis_angle([0, 1, 0], rs.uniform(0, 2 * math.pi)),
               scale=[s, s * rs.uniform(0.85, 1.25), s])
    rock_root = w.node("Rocks")
    for k in range(100):
        x, z = sample_spot(4.0)
        s = rs.uniform(0.6, 2.2)
        scl = [s * rs.uniform(0.8, 1.2), s * rs.uniform(0.7, 1.1), s * rs.uniform(0.8, 1.2)]
        rot = quat_mul(quat_axis_angle([0, 1, 0], rs.uniform(0, 2 * math.pi)),
                       quat_axis_angle([1, 0, 0], math.radians(rs.uniform(-15, 15))))
        w.node("Rock_%03d" % k, parent=rock_root, mesh=mesh_rock,
               translation=[x, float(terrain_height(x, z)) - 0.25 * scl[1], z], rotation=rot, scale=scl)

    cam = w.camera("CityCamera", 0.8, 16.0 / 9.0, 0.5, 3000.0)
    eye = [-330.0, 190.0, 330.0]
    w.node("Camera", camera=cam, translation=eye, rotation=quat_look(eye, [0.0, 15.0, 0.0]))
    w.write_glb(path)


# ============================================================================
# Checker: parse the files back and validate
# ============================================================================
COMP_DT = {BYTE: np.int8, UBYTE: np.uint8, SHORT: np.int16, USHORT: np.uint16, UINT: np.uint32, FLOAT: np.float32}
TYPE_N = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
# primitives allowed to lack NORMAL (documented in README.md)
NO_NORMAL_OK = {("foliage_instanced.glb", "Bench_NoNormals")}


class CheckError(Exception):
    pass


def load_gltf(path, errs):
    raw = open(path, "rb").read()
    if path.endswith(".glb"):
        magic, ver, length = struct.unpack_from("<III", raw, 0)
        if magic != 0x46546C67 or ver != 2:
            errs.append("bad GLB header")
        if length != len(raw):
            errs.append("GLB length %d != file size %d" % (length, len(raw)))
        clen, ctype = struct.unpack_from("<II", raw, 12)
        if ctype != 0x4E4F534A or clen % 4:
            errs.append("JSON chunk type/length invalid")
        jbytes = raw[20:20 + clen]
        text = jbytes.decode("utf-8")
        stripped = text.rstrip(" ")
        if len(jbytes) - len(stripped.encode()) > 3 or not stripped.endswith("}"):
            errs.append("JSON chunk not padded with (at most 3) spaces")
        j = json.loads(text)
        bufs = []
        off = 20 + clen
        if off < len(raw):
            blen, btype = struct.unpack_from("<II", raw, off)
            if btype != 0x004E4942 or blen % 4:
                errs.append("BIN chunk type/length invalid")
            bin_data = raw[off + 8: off + 8 + blen]
            declared = j["buffers"][0]["byteLength"]
            if "uri" in j["buffers"][0]:
                errs.append("GLB buffer 0 must not have a uri")
            if not (declared <= blen <= declared + 3):
                errs.append("BIN chunk length %d vs buffer.byteLength %d" % (blen, declared))
            if any(bin_data[declared:]):
                errs.append("BIN chunk padding not zero")
            if off + 8 + blen != len(raw):
                errs.append("trailing bytes after BIN chunk")
            bufs.append(bin_data[:declared])
    else:
        j = json.loads(raw.decode("utf-8"))
        bufs = []
        for b in j["buffers"]:
            data = open(os.path.join(os.path.dirname(path), b["uri"]), "rb").read()
            if len(data) != b["byteLength"]:
                errs.append("buffer %s size %d != byteLength %d" % (b["uri"], len(data), b["byteLength"]))
            bufs.append(data)
    return j, bufs


def read_accessor(j, bufs, ai, errs):
    a = j["accessors"][ai]
    if a["componentType"] not in COMP_DT or a["type"] not in TYPE_N:
        errs.append("accessor %d: bad componentType/type" % ai)
        return None
    dt = np.dtype(COMP_DT[a["componentType"]])
    n = TYPE_N[a["type"]]
    bv = j["bufferViews"][a["bufferView"]]
    elem = n * dt.itemsize
    stride = bv.get("byteStride", elem)
    aoff, voff = a.get("byteOffset", 0), bv.get("byteOffset", 0)
    if aoff % dt.itemsize or (aoff + voff) % dt.itemsize:
        errs.append("accessor %d misaligned" % ai)
    if aoff + stride * (a["count"] - 1) + elem > bv["byteLength"]:
        errs.append("accessor %d overruns its bufferView" % ai)
    buf = bufs[bv["buffer"]]
    arr = np.ndarray(shape=(a["count"], n), dtype=dt, buffer=buf, offset=voff + aoff,
                     strides=(stride, dt.itemsize)).copy()
    return arr


def tri_area3(p, t):
    return 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), axis=1)


def tri_area2(u, t):
    a, b, c = u[t[:, 0]], u[t[:, 1]], u[t[:, 2]]
    return 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])


def raster_coverage(uv, tris, res=512):
    """Counts, per pixel centre, how many UV triangles strictly contain it.
    Returns (#pixels covered more than once, #pixels covered)."""
    P = uv[tris].astype(np.float64) * res
    a, b, c = P[:, 0], P[:, 1], P[:, 2]
    sgn = np.sign((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    lo = np.clip(np.ceil(P.min(1) - 0.5).astype(np.int64), 0, res - 1)
    hi = np.clip(np.floor(P.max(1) - 0.5).astype(np.int64), 0, res - 1)
    ext = np.maximum(hi - lo + 1, 0).max(1)
    cov = np.zeros(res * res, np.int64)
    K = 1
    while True:
        sel = np.nonzero((ext > K // 2) & (ext <= K))[0] if K > 1 else np.nonzero(ext == 1)[0]
        step = max(1, 4_000_000 // (K * K))
        for s0 in range(0, len(sel), step):
            ii = sel[s0:s0 + step]
            gx = lo[ii, 0, None, None] + np.arange(K)[None, None, :]
            gy = lo[ii, 1, None, None] + np.arange(K)[None, :, None]
            px, py = gx + 0.5, gy + 0.5
            inside = (gx <= hi[ii, 0, None, None]) & (gy <= hi[ii, 1, None, None])
            for e0, e1 in ((a, b), (b, c), (c, a)):
                ex = (e1[ii, 0] - e0[ii, 0])[:, None, None]
                ey = (e1[ii, 1] - e0[ii, 1])[:, None, None]
                ef = ex * (py - e0[ii, 1, None, None]) - ey * (px - e0[ii, 0, None, None])
                inside &= ef * sgn[ii, None, None] > 1e-6
            cov += np.bincount((gy * res + gx)[inside], minlength=res * res)
        if K >= ext.max(initial=0):
            break
        K *= 2
    return int((cov > 1).sum()), int((cov > 0).sum())


def chart_boxes(uv, tris):
    """Connected components of UV triangles (vertices welded by UV value) ->
    per-chart bounding boxes in UV units."""
    key = np.round(uv.astype(np.float64) * (1 << 22)).astype(np.int64)
    _, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    t = inv[tris]
    lab = np.arange(inv.max() + 1)
    while True:
        m = lab[t].min(axis=1)
        new = lab.copy()
        for c in range(3):
            np.minimum.at(new, t[:, c], m)
        new = new[new]
        if np.array_equal(new, lab):
            break
        lab = new
    tl = lab[t[:, 0]]
    roots, tri_chart = np.unique(tl, return_inverse=True)
    boxes = np.zeros((len(roots), 4))
    boxes[:, :2], boxes[:, 2:] = np.inf, -np.inf
    P = uv[tris].astype(np.float64)
    np.minimum.at(boxes[:, 0], tri_chart, P[:, :, 0].min(1))
    np.minimum.at(boxes[:, 1], tri_chart, P[:, :, 1].min(1))
    np.maximum.at(boxes[:, 2], tri_chart, P[:, :, 0].max(1))
    np.maximum.at(boxes[:, 3], tri_chart, P[:, :, 1].max(1))
    return boxes


def collect_extensions(obj, found):
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k == "extensions" and isinstance(v, dict):
                found.update(v.keys())
            collect_extensions(v, found)
    elif isinstance(obj, list):
        for v in obj:
            collect_extensions(v, found)


def check_file(path):
    fname = os.path.basename(path)
    errs, notes = [], []
    j, bufs = load_gltf(path, errs)
    if j.get("asset", {}).get("version") != "2.0":
        errs.append("asset.version must be '2.0'")
    found = set()
    collect_extensions(j, found)
    if found != set(j.get("extensionsUsed", [])):
        errs.append("extensionsUsed %s != extensions present %s" % (j.get("extensionsUsed"), sorted(found)))
    for i, bv in enumerate(j["bufferViews"]):
        if bv.get("byteOffset", 0) % 4:
            errs.append("bufferView %d not 4-byte aligned" % i)
        if bv.get("byteOffset", 0) + bv["byteLength"] > j["buffers"][bv["buffer"]]["byteLength"]:
            errs.append("bufferView %d overruns buffer" % i)
        if "byteStride" in bv:
            if bv["byteStride"] % 4 or not 4 <= bv["byteStride"] <= 252:
                errs.append("bufferView %d byteStride %d invalid" % (i, bv["byteStride"]))
            if bv.get("target") == ELEMENT_ARRAY_BUFFER:
                errs.append("index bufferView %d has byteStride" % i)
    # images
    for i, im in enumerate(j.get("images", [])):
        bv = j["bufferViews"][im["bufferView"]]
        data = bufs[bv["buffer"]][bv.get("byteOffset", 0): bv.get("byteOffset", 0) + bv["byteLength"]]
        if im.get("mimeType") != "image/png" or data[:8] != b"\x89PNG\r\n\x1a\n":
            errs.append("image %d is not a PNG" % i)
        else:
            wd, ht, depth, ctype = struct.unpack(">IIBB", data[16:26])
            notes.append("image %s %dx%d %s" % (im.get("name", i), wd, ht, {2: "RGB", 6: "RGBA"}.get(ctype)))
    # node hierarchy: each node has at most one parent, roots are scene nodes, no cycles
    parents = {}
    for i, nd in enumerate(j["nodes"]):
        if "matrix" in nd and any(k in nd for k in ("translation", "rotation", "scale")):
            errs.append("node %d has both matrix and TRS" % i)
        if "rotation" in nd and abs(np.linalg.norm(nd["rotation"]) - 1) > 1e-6:
            errs.append("node %d rotation not unit" % i)
        for c in nd.get("children", []):
            if c in parents:
                errs.append("node %d has two parents" % c)
            parents[c] = i
    instances = {}
    depth_max = 0

    def visit(ni, depth, seen):
        nonlocal depth_max
        if ni in seen:
            errs.append("cycle at node %d" % ni)
            return
        seen.add(ni)
        depth_max = max(depth_max, depth)
        nd = j["nodes"][ni]
        if "mesh" in nd:
            instances[nd["mesh"]] = instances.get(nd["mesh"], 0) + 1
        for c in nd.get("children", []):
            visit(c, depth + 1, seen)

    seen = set()
    for r in j["scenes"][j.get("scene", 0)]["nodes"]:
        if r in parents:
            errs.append("scene root %d has a parent" % r)
        visit(r, 0, seen)
    # meshes
    rows = []
    for mi, mesh in enumerate(j["meshes"]):
        mname = mesh.get("name", str(mi))
        all_uv1, all_tris, base = [], [], 0
        st = dict(tris=0, verts=0, min_area=np.inf, min_uv_area=np.inf, uv_min=np.inf, uv_max=-np.inf,
                  wind_bad=0, no_normal=False, idx_types=set())
        for pi, prim in enumerate(mesh["primitives"]):
            at = prim["attributes"]
            if prim.get("mode", 4) != 4:
                errs.append("%s/%d: mode must be TRIANGLES" % (mname, pi))
            for req in ("POSITION", "TEXCOORD_0", "TEXCOORD_1"):
                if req not in at:
                    errs.append("%s/%d: missing %s" % (mname, pi, req))
            if "NORMAL" not in at:
                st["no_normal"] = True
                if (fname, mname) not in NO_NORMAL_OK:
                    errs.append("%s/%d: missing NORMAL" % (mname, pi))
            data = {}
            for nm, ai in at.items():
                acc = j["accessors"][ai]
                bv = j["bufferViews"][acc["bufferView"]]
                if bv.get("target", ARRAY_BUFFER) != ARRAY_BUFFER:
                    errs.append("%s: vertex accessor in non-vertex view" % nm)
                if "byteStride" not in bv and (TYPE_N[acc["type"]] * np.dtype(COMP_DT[acc["componentType"]]).itemsize) % 4:
                    errs.append("%s: vertex element not 4-byte aligned" % nm)
                want = {"POSITION": ("VEC3", FLOAT), "NORMAL": ("VEC3", FLOAT),
                        "TEXCOORD_0": ("VEC2", FLOAT), "TEXCOORD_1": ("VEC2", FLOAT)}.get(nm)
                if want and (acc["type"], acc["componentType"]) != want:
                    errs.append("%s/%d %s: type %s/%d" % (mname, pi, nm, acc["type"], acc["componentType"]))
                data[nm] = read_accessor(j, bufs, ai, errs)
            counts = {len(v) for v in data.values()}
            if len(counts) != 1:
                errs.append("%s/%d: attribute counts differ" % (mname, pi))
            pos = data["POSITION"].astype(np.float64)
            pacc = j["accessors"][at["POSITION"]]
            if "min" not in pacc or "max" not in pacc:
                errs.append("%s/%d: POSITION min/max missing" % (mname, pi))
            elif (np.float32(pacc["min"]) != data["POSITION"].min(0)).any() or \
                    (np.float32(pacc["max"]) != data["POSITION"].max(0)).any():
                errs.append("%s/%d: POSITION min/max do not match data" % (mname, pi))
            iacc = j["accessors"][prim["indices"]]
            if iacc["componentType"] not in (UBYTE, USHORT, UINT) or iacc["type"] != "SCALAR" or iacc.get("normalized"):
                errs.append("%s/%d: bad index accessor" % (mname, pi))
            if j["bufferViews"][iacc["bufferView"]].get("target", ELEMENT_ARRAY_BUFFER) != ELEMENT_ARRAY_BUFFER:
                errs.append("%s/%d: index view target" % (mname, pi))
            st["idx_types"].add({UBYTE: "u8", USHORT: "u16", UINT: "u32"}[iacc["componentType"]])
            idx = read_accessor(j, bufs, prim["indices"], errs).reshape(-1).astype(np.int64)
            if len(idx) % 3 or idx.max() >= len(pos):
                errs.append("%s/%d: bad index data" % (mname, pi))
                continue
            t = idx.reshape(-1, 3)
            area = tri_area3(pos, t)
            uv1 = data["TEXCOORD_1"].astype(np.float64)
            uva = tri_area2(uv1, t)
            st["tris"] += len(t)
            st["verts"] += len(pos)
            st["min_area"] = min(st["min_area"], area.min())
            st["min_uv_area"] = min(st["min_uv_area"], np.abs(uva).min())
            st["uv_min"] = min(st["uv_min"], uv1.min())
            st["uv_max"] = max(st["uv_max"], uv1.max())
            if "NORMAL" in data:
                nrm = data["NORMAL"].astype(np.float64)
                if np.abs(np.linalg.norm(nrm, axis=1) - 1).max() > 1e-3:
                    errs.append("%s/%d: NORMAL not unit length" % (mname, pi))
                g = np.cross(pos[t[:, 1]] - pos[t[:, 0]], pos[t[:, 2]] - pos[t[:, 0]])
                st["wind_bad"] += int(((g * nrm[t].sum(1)).sum(1) <= 0).sum())
            all_uv1.append(uv1)
            all_tris.append(t + base)
            base += len(pos)
        uv1 = np.concatenate(all_uv1)
        tris = np.concatenate(all_tris)
        boxes = chart_boxes(uv1, tris)
        gap = np.inf
        if len(boxes) > 1:
            A, B = boxes[:, None, :], boxes[None, :, :]
            g = np.maximum.reduce([B[..., 0] - A[..., 2], A[..., 0] - B[..., 2],
                                   B[..., 1] - A[..., 3], A[..., 1] - B[..., 3]])
            np.fill_diagonal(g, np.inf)
            gap = g.min() * ATLAS_RES
        border = min(boxes[:, :2].min(), (1 - boxes[:, 2:]).min()) * ATLAS_RES
        overl, covered = raster_coverage(uv1, tris)
        st.update(charts=len(boxes), gap=gap, border=border, overlap=overl, fill=covered / 512.0 ** 2,
                  inst=instances.get(mi, 0))
        if st["uv_min"] < 0 or st["uv_max"] > 1:
            errs.append("%s: TEXCOORD_1 outside [0,1]" % mname)
        if st["min_area"] <= 1e-9 or st["min_uv_area"] <= 1e-12:
            errs.append("%s: zero-area triangle" % mname)
        if overl:
            errs.append("%s: %d lightmap texels (512^2) covered twice" % (mname, overl))
        if gap < GUTTER - 1e-6 or border < MARGIN - 1e-6:
            errs.append("%s: chart gutter %.2f / border %.2f texels < 2" % (mname, gap, border))
        if st["wind_bad"]:
            errs.append("%s: %d triangles wound against their normals" % (mname, st["wind_bad"]))
        rows.append((mname, st))
    return j, rows, errs, notes, depth_max


def check_all(paths):
    ok = True
    for path in paths:
        fname = os.path.basename(path)
        j, rows, errs, notes, depth = check_file(path)
        size = os.path.getsize(path)
        if path.endswith(".gltf"):
            size += sum(os.path.getsize(os.path.join(os.path.dirname(path), b["uri"])) for b in j["buffers"])
        uniq = sum(st["tris"] for _, st in rows)
        world = sum(st["tris"] * st["inst"] for _, st in rows)
        inst_world = sum(st["tris"] * st["inst"] for _, st in rows if st["inst"] > 1)
        print("=" * 100)
        print("%s: %.2f MB, %d nodes (max depth %d), %d meshes, %d materials, %d textures, %d lights, %d cameras"
              % (fname, size / 1e6, len(j["nodes"]), depth, len(j["meshes"]), len(j["materials"]),
                 len(j.get("textures", [])), len(j.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])),
                 len(j.get("cameras", []))))
        print("  unique triangles %d, world triangles (after instancing) %d, world tris from instanced meshes %d (%.1f%%)"
              % (uniq, world, inst_world, 100.0 * inst_world / max(world, 1)))
        for n in notes:
            print("  " + n)
        shown = rows if len(rows) <= 12 else [r for r in rows if not r[0].startswith("Building_")]
        hdr = "  %-18s %5s %8s %7s %4s %6s %7s %9s %9s %6s %6s %5s %5s %4s"
        print(hdr % ("mesh", "inst", "tris", "verts", "idx", "charts", "fill%", "minArea", "minUVArea",
                     "gap", "border", "ovl", "wind", "nrm"))
        fmt = "  %-18s %5d %8d %7d %4s %6d %7.1f %9.2e %9.2e %6s %6.1f %5d %5d %4s"
        for name, st in shown:
            print(fmt % (name[:18], st["inst"], st["tris"], st["verts"], "/".join(sorted(st["idx_types"])),
                         st["charts"], 100 * st["fill"], st["min_area"], st["min_uv_area"],
                         "-" if st["gap"] == np.inf else "%.1f" % st["gap"], st["border"], st["overlap"],
                         st["wind_bad"], "no" if st["no_normal"] else "yes"))
        if len(shown) != len(rows):
            b = [st for name, st in rows if name.startswith("Building_")]
            print(fmt % ("Building_* (%d)" % len(b), sum(s["inst"] for s in b), sum(s["tris"] for s in b),
                         sum(s["verts"] for s in b), "/".join(sorted(set().union(*[s["idx_types"] for s in b]))),
                         sum(s["charts"] for s in b), 100 * np.mean([s["fill"] for s in b]),
                         min(s["min_area"] for s in b), min(s["min_uv_area"] for s in b),
                         "%.1f" % min(s["gap"] for s in b), min(s["border"] for s in b),
                         sum(s["overlap"] for s in b), sum(s["wind_bad"] for s in b), "yes"))
            print("    (Building_* row: sums, except fill%% = mean, minArea/gap/border = min over %d meshes)" % len(b))
        if errs:
            ok = False
            for e in errs:
                print("  ERROR: " + e)
        else:
            print("  all checks passed")
    print("=" * 100)
    print("columns: inst = nodes referencing the mesh; fill% = lightmap texels covered at 512^2; minArea = m^2;")
    print("         minUVArea = TEXCOORD_1 units^2; gap/border = min texels (at 256^2) between chart rectangles /")
    print("         to the atlas edge; ovl = texels (512^2) covered by 2+ triangles; wind = triangles wound")
    print("         clockwise w.r.t. their normals; nrm = NORMAL present")
    return ok


OUTPUTS = ["cornell_box.gltf", "foliage_instanced.glb", "procedural_city.glb"]


def main(argv):
    paths = [os.path.join(HERE, f) for f in OUTPUTS]
    if "--check" not in argv:
        make_cornell_box(paths[0])
        make_foliage(paths[1])
        make_city(paths[2])
        for p in paths + [os.path.join(HERE, "cornell_box.bin")]:
            print("wrote %s (%d bytes)" % (os.path.relpath(p, os.path.dirname(HERE)), os.path.getsize(p)))
    if "--no-check" in argv:
        return 0
    return 0 if check_all(paths) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
