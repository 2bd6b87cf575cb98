"""Scene 2, foliage_instanced.glb: instancing (40 plant nodes, 3-level node
tree, a matrix node), alpha-tested cards, embedded PNG textures, a mesh without
NORMAL, KHR_lights_punctual. See scenes/README.md.
"""
import math

import numpy as np

from .geometry import MeshBuilder, quat_axis_angle, quat_dir, quat_look, quat_mul
from .gltf_writer import (CLAMP_TO_EDGE, LINEAR, LINEAR_MIPMAP_LINEAR, REPEAT, GltfWriter,
                          png_bytes)


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
