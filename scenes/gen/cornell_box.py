"""Scene 1, cornell_box.gltf + cornell_box.bin: the Cornell box as a .gltf with
an external buffer, interleaved vertex data (byteStride 40), emissive area
light with KHR_materials_emissive_strength. See scenes/README.md.
"""
import math

import numpy as np

from .geometry import MeshBuilder
from .gltf_writer import GltfWriter


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
