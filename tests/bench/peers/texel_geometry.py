"""What each lightmap texel is on: material and world position, from the glTF.

Used by compare.py to split the agreement of the converged maps by the
receiver's material and into texels near a crease (a wall meeting the floor,
a box standing on the ground) and the rest. The receiver's own material does
not enter its lightmap value (both renderers bake irradiance); the split shows
where the light bounced off the GGX and metal materials around it lands.

Rasterises every primitive's TEXCOORD_1 triangles at texel centres (u = (x +
0.5) / res, v = (y + 0.5) / res: row 0 = top = v 0, Luxel's layout), the
last triangle drawn winning where charts overlap (compare.py's interior mask
already leaves chart borders out).
"""
import json
import math
import os
import struct

import numpy as np

_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}


def _load(path):
    """(glTF JSON, list of buffer bytes) of a .gltf (external or data: buffers) or .glb"""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        n = struct.unpack_from("<I", data, 12)[0]
        gj = json.loads(data[20:20 + n])
        off = 20 + n
        bins = []
        if off + 8 <= len(data):
            m = struct.unpack_from("<I", data, off)[0]
            bins.append(data[off + 8:off + 8 + m])
        return gj, bins
    gj = json.loads(data)
    bins = []
    for b in gj.get("buffers", []):
        uri = b["uri"]
        if uri.startswith("data:"):
            import base64
            bins.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            with open(os.path.join(os.path.dirname(path), uri), "rb") as f:
                bins.append(f.read())
    return gj, bins


def _accessor(gj, bins, i):
    a = gj["accessors"][i]
    bv = gj["bufferViews"][a["bufferView"]]
    dt = np.dtype(_DTYPES[a["componentType"]])
    nc = _COMPONENTS[a["type"]]
    start = bv.get("byteOffset", 0) + a.get("byteOffset", 0)
    stride = bv.get("byteStride") or dt.itemsize * nc
    buf = bins[bv["buffer"]]
    raw = np.frombuffer(buf, np.uint8, count=stride * (a["count"] - 1) + dt.itemsize * nc, offset=start)
    out = np.lib.stride_tricks.as_strided(raw, (a["count"], nc * dt.itemsize), (stride, 1)).copy()
    out = out.view(dt).reshape(a["count"], nc).astype(np.float64)
    if a.get("normalized"):
        out /= float(np.iinfo(dt).max)
    return out


def _local_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"], np.float64).reshape(4, 4).T
    t = node.get("translation", [0, 0, 0])
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    s = node.get("scale", [1, 1, 1])
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r * np.array(s)[None, :]
    m[:3, 3] = t
    return m


def rasterise(path, res):
    """material index per texel (-1: none), world position per texel, material
    names, world triangles (T, 3, 3) and their unit normals"""
    gj, bins = _load(path)
    mat_id = np.full((res, res), -1, np.int32)
    pos = np.zeros((res, res, 3))
    nrm = np.zeros((res, res, 3))
    tris_all, norms_all = [], []
    scene = gj.get("scenes", [{}])[gj.get("scene", 0)]
    stack = [(n, np.eye(4)) for n in scene.get("nodes", [])]
    while stack:
        ni, parent = stack.pop()
        node = gj["nodes"][ni]
        world = parent @ _local_matrix(node)
        stack += [(c, world) for c in node.get("children", [])]
        if "mesh" not in node:
            continue
        for prim in gj["meshes"][node["mesh"]]["primitives"]:
            at = prim["attributes"]
            if prim.get("mode", 4) != 4 or "TEXCOORD_1" not in at:
                continue
            p = _accessor(gj, bins, at["POSITION"])
            p = p @ world[:3, :3].T + world[:3, 3]
            uv = _accessor(gj, bins, at["TEXCOORD_1"])
            idx = (_accessor(gj, bins, prim["indices"]).astype(np.int64).ravel()
                   if "indices" in prim else np.arange(len(p)))
            idx = idx[:len(idx) // 3 * 3].reshape(-1, 3)
            tp, tuv = p[idx], uv[idx] * res - 0.5      # texel-centre coordinates
            n = np.cross(tp[:, 1] - tp[:, 0], tp[:, 2] - tp[:, 0])
            ln = np.linalg.norm(n, axis=1)
            keep = ln > 0
            tris_all.append(tp[keep])
            norms_all.append(n[keep] / ln[keep, None])
            m = prim.get("material", -1)
            for t in range(len(idx)):
                if not keep[t]:
                    continue
                a, b, c = tuv[t]
                x0 = max(int(math.floor(min(a[0], b[0], c[0]))), 0)
                y0 = max(int(math.floor(min(a[1], b[1], c[1]))), 0)
                x1 = min(int(math.ceil(max(a[0], b[0], c[0]))), res - 1)
                y1 = min(int(math.ceil(max(a[1], b[1], c[1]))), res - 1)
                if x1 < x0 or y1 < y0:
                    continue
                xs, ys = np.meshgrid(np.arange(x0, x1 + 1), np.arange(y0, y1 + 1))
                det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
                if abs(det) < 1e-12:
                    continue
                l1 = ((xs - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (ys - a[1])) / det
                l2 = ((b[0] - a[0]) * (ys - a[1]) - (xs - a[0]) * (b[1] - a[1])) / det
                l0 = 1 - l1 - l2
                inside = (l0 >= -1e-6) & (l1 >= -1e-6) & (l2 >= -1e-6)
                if not inside.any():
                    continue
                yy, xx = ys[inside], xs[inside]
                mat_id[yy, xx] = m
                w = np.stack([l0[inside], l1[inside], l2[inside]], 1)
                pos[yy, xx] = w @ tp[t]
                nrm[yy, xx] = norms_all[-1][keep[:t].sum()]
    names = [mm.get("name", f"material {i}") for i, mm in enumerate(gj.get("materials", []))]
    tris = np.concatenate(tris_all) if tris_all else np.zeros((0, 3, 3))
    norms = np.concatenate(norms_all) if norms_all else np.zeros((0, 3))
    return mat_id, pos, nrm, names, tris, norms


def _point_triangle_distance(p, tri):
    """distances (N, T) from points p (N, 3) to triangles tri (T, 3, 3)"""
    a, b, c = tri[:, 0][None], tri[:, 1][None], tri[:, 2][None]
    q = p[:, None, :]
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = np.maximum((n * n).sum(-1), 1e-30)
    # barycentrics of the projection
    w = q - a
    v1 = (np.cross(w, ac) * n).sum(-1) / nn
    v2 = (np.cross(ab, w) * n).sum(-1) / nn
    plane = np.abs((w * n).sum(-1)) / np.sqrt(nn)
    inside = (v1 >= 0) & (v2 >= 0) & (v1 + v2 <= 1)

    def seg(s0, s1):
        d = s1 - s0
        t = np.clip(((q - s0) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-30), 0, 1)
        return np.linalg.norm(q - (s0 + t[..., None] * d), axis=-1)

    edge = np.minimum(np.minimum(seg(a, b), seg(b, c)), seg(c, a))
    return np.where(inside, plane, edge)


def near_crease(pos, nrm, texels, tris, norms, frac=0.05, max_work=4e7):
    """bool per texel of `texels` (mask): its world point lies within frac x the
    scene's largest extent of a triangle whose plane is turned by more than
    ~25 degrees from the texel's and which rises above the texel's plane (a
    wall meeting the floor, a box on the ground: a concave crease or contact,
    not the texel's own convex edge); (None, None) when the scene is too large
    for this brute force"""
    p, n = pos[texels], nrm[texels]
    if len(p) * len(tris) > max_work:
        return None, None
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    d0 = frac * float((hi - lo).max())
    out = np.zeros(len(p), bool)
    for s in range(0, len(p), 256):
        dist = _point_triangle_distance(p[s:s + 256], tris)
        turned = np.abs(n[s:s + 256] @ norms.T) < 0.9
        # height of the triangle's highest vertex above the texel's plane
        pn = n[s:s + 256]
        rise = (np.einsum("tvk,nk->ntv", tris, pn).max(axis=2)
                - (p[s:s + 256] * pn).sum(1)[:, None])
        out[s:s + 256] = ((dist < d0) & turned & (rise > 0.5 * d0)).any(1)
    return out, d0
