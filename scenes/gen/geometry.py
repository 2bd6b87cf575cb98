"""Geometry shared by the scene modules: small math helpers, the lightmap
chart packer and MeshBuilder, which turns charts (connected pieces of surface
with a flat 2D parameterisation in metres) into glTF primitives with packed
TEXCOORD_1.

Lightmap conventions (see scenes/README.md): all charts of one mesh share one
texel density; chart rectangles are >= GUTTER texels apart and >= MARGIN texels
from the atlas edge, measured at ATLAS_RES x ATLAS_RES. MeshBuilder.build()
reads ATLAS_RES and pack_charts from this module at call time, so a caller may
rebind both for another atlas size (tests/bench/peers/make_scenes.py does).
"""
import math

import numpy as np

ATLAS_RES = 256   # reference lightmap resolution the gutter is measured at
GUTTER = 2        # texels between chart rectangles
MARGIN = 2        # texels between charts and the atlas border


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

