"""Scene 3, procedural_city.glb: a large scene (549,574 world triangles):
noise terrain, 163 unique buildings, instanced trees and rocks, all geometry in
shared bufferViews. See scenes/README.md.
"""
import math

import numpy as np

from .geometry import (ATLAS_RES, MARGIN, MeshBuilder, fix_winding, grid_tris, normalize,
                       quat_axis_angle, quat_look, quat_mul)
from .gltf_writer import GltfWriter


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
