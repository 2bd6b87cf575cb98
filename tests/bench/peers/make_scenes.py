#!/usr/bin/env python3
"""Write the peer-comparison scenes (deterministic; numpy + stdlib only).

  python3 tests/bench/peers/make_scenes.py OUTDIR

writes OUTDIR/sky_plane.gltf, OUTDIR/lights_plane.gltf (calibrations),
OUTDIR/sky_courtyard.gltf and OUTDIR/lights_courtyard.gltf.
Reuses the glTF writer and chart packer of the scene generator
(scenes/gen/gltf_writer.py, scenes/gen/geometry.py; imported, not modified);
charts are packed for a 64x64 atlas with 2 texels of gutter, so that a 64^2
bake has interior texels on every chart.

  sky_plane      two 2 m quads lit only by a constant sky: one facing up at
                 the origin, one vertical (facing +z) 200 m away. Each sees
                 one hemisphere of unoccluded sky (the other quad subtends
                 < 1e-4 sr), so E = pi * L on both, in Luxel and in Blender.
                 It pins the unit conversion (Blender's diffuse pass = E/pi)
                 and the sky convention (full sphere, not only above the
                 horizon: the vertical quad sees half a hemisphere below it).
  sky_courtyard  a 6 x 6 m grey ground, an L of two coloured walls, a white
                 box and a floating white roof slab (shadowed, mostly
                 indirectly lit ground under it). Lit only by the sky.
  lights_plane   KHR_lights_punctual units and cone: three 2 m quads 20 m
                 apart, a point light 1 m over the first, a spot (inner 20,
                 outer 40 degrees) 1.5 m over the second, a sun over all; the
                 third quad is a rough gold metal lit by the sun alone (the
                 baked value is irradiance whatever the receiver).
  lights_courtyard  the courtyard lit by a sun, a point and a spot light (no
                 sky), with what users bake: a textured GGX ground (checker
                 base colour, roughness 0.6), a glossy dielectric wall
                 (roughness 0.35), a gold box (metallic 1, roughness 0.3), a
                 half-metallic slab (metallic 0.5, roughness 0.5).
sky_* materials are metallic 0, roughness 1 (Luxel: exact Lambert) and
one-sided; all surfaces are closed boxes (bottom faces on the ground left out)
or the ground quad, so no back face is ever lit. Light intensities are
radiometric as Luxel reads them (kernels/shared/light.h: point/spot W/sr,
directional W/m^2).
"""
import functools
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True  # do not leave __pycache__ in scenes/
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "scenes"))
from gen import geometry  # noqa: E402
from gen.gltf_writer import GltfWriter, png_bytes  # noqa: E402

RES = 64
# MeshBuilder.build() looks both up in the geometry module when it runs.
geometry.ATLAS_RES = RES
geometry.pack_charts = functools.partial(geometry.pack_charts, res=RES, gutter=2, margin=2)


def lambert(w, name, rgb):
    return w.material(name, [*rgb, 1.0], metallic=0.0, roughness=1.0, doubleSided=False)


def sky_plane(path):
    w = GltfWriter("SkyPlane")
    grey = lambert(w, "Grey", [0.5, 0.5, 0.5])
    mb = geometry.MeshBuilder()
    mb.quad(grey, [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], [0, 1, 0])
    mb.quad(grey, [[199, -1, 0], [201, -1, 0], [201, 1, 0], [199, 1, 0]], [0, 0, 1])
    w.node("SkyPlane", mesh=w.mesh("SkyPlane", mb.build()))
    w.write_gltf(path)


def sky_courtyard(path):
    w = GltfWriter("SkyCourtyard")
    ground = lambert(w, "Ground", [0.5, 0.5, 0.5])
    white = lambert(w, "White", [0.8, 0.8, 0.8])
    red = lambert(w, "Red", [0.75, 0.25, 0.2])
    green = lambert(w, "Green", [0.2, 0.6, 0.25])
    mb = geometry.MeshBuilder()
    mb.quad(ground, [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]], [0, 1, 0])
    mb.box(red, [0.0, 1.0, -2.5], [5.0, 2.0, 0.3], skip=("-y",))      # back wall
    mb.box(green, [-2.5, 1.0, 0.0], [0.3, 2.0, 4.7], skip=("-y",))    # left wall
    mb.box(white, [1.2, 0.5, 1.0], [1.2, 1.0, 1.2], skip=("-y",))     # box
    mb.box(white, [-1.0, 1.4, -1.0], [2.2, 0.15, 2.2])                # roof slab
    w.node("SkyCourtyard", mesh=w.mesh("SkyCourtyard", mb.build()))
    w.write_gltf(path)


def add_lights(w, lights):
    """KHR_lights_punctual: lights = [(light dict, node props)]"""
    w.j["extensionsUsed"].append("KHR_lights_punctual")
    w.j.setdefault("extensions", {})["KHR_lights_punctual"] = {"lights": [d for d, _ in lights]}
    for i, (d, props) in enumerate(lights):
        w.node(d["name"], extensions={"KHR_lights_punctual": {"light": i}}, **props)


def aim(position, target):
    """node props placing a light at position, pointing (local -Z) at target"""
    d = np.subtract(target, position)
    up = (0.0, 0.0, 1.0) if abs(d[1]) > 0.99 * np.linalg.norm(d) else (0.0, 1.0, 0.0)
    return {"translation": [float(x) for x in position], "rotation": geometry.quat_look(position, target, up)}


def sun_props(direction):
    up = (0.0, 0.0, 1.0) if abs(direction[1]) > 0.99 * np.linalg.norm(direction) else (0.0, 1.0, 0.0)
    return {"rotation": geometry.quat_look((0.0, 0.0, 0.0), direction, up)}


def lights_plane(path):
    w = GltfWriter("LightsPlane")
    grey = lambert(w, "Grey", [0.5, 0.5, 0.5])
    gold = w.material("Gold", [1.0, 0.78, 0.34, 1.0], metallic=1.0, roughness=0.3, doubleSided=False)
    mb = geometry.MeshBuilder()
    for x0, mat in ((0.0, grey), (20.0, grey), (40.0, gold)):
        mb.quad(mat, [[x0 - 1, 0, -1], [x0 + 1, 0, -1], [x0 + 1, 0, 1], [x0 - 1, 0, 1]], [0, 1, 0])
    w.node("LightsPlane", mesh=w.mesh("LightsPlane", mb.build()))
    add_lights(w, [
        ({"name": "Point", "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 5.0},
         {"translation": [0.0, 1.0, 0.0]}),
        ({"name": "Spot", "type": "spot", "color": [0.8, 0.9, 1.0], "intensity": 8.0,
          "spot": {"innerConeAngle": math.radians(20), "outerConeAngle": math.radians(40)}},
         aim([20.0, 1.5, 0.0], [20.0, 0.0, 0.0])),
        ({"name": "Sun", "type": "directional", "color": [1.0, 1.0, 1.0], "intensity": 2.0},
         sun_props([-0.3, -1.0, -0.2])),
    ])
    w.write_gltf(path)


def checker(n=32, tiles=4, a=(200, 190, 170), b=(90, 100, 120)):
    """RGB8 checker of tiles x tiles squares (sRGB values)"""
    y, x = np.mgrid[0:n, 0:n] * tiles // n
    img = np.where(((x + y) % 2 == 0)[..., None], np.array(a), np.array(b))
    return img.astype(np.uint8)


def lights_courtyard(path):
    w = GltfWriter("LightsCourtyard")
    img = w.image("checker", png_bytes(checker()))
    w.j.setdefault("textures", []).append({"source": img})
    ground = w.material("TexturedGround", [1.0, 1.0, 1.0, 1.0], metallic=0.0, roughness=0.6,
                        base_texture=len(w.j["textures"]) - 1, doubleSided=False)
    red = lambert(w, "Red", [0.75, 0.25, 0.2])
    green = w.material("GlossyGreen", [0.2, 0.6, 0.25, 1.0], metallic=0.0, roughness=0.35,
                       doubleSided=False)
    gold = w.material("Gold", [1.0, 0.78, 0.34, 1.0], metallic=1.0, roughness=0.3, doubleSided=False)
    slab = w.material("HalfMetal", [0.8, 0.8, 0.8, 1.0], metallic=0.5, roughness=0.5, doubleSided=False)
    mb = geometry.MeshBuilder()
    # ground: uv0 in metres / 2 (the 4x4 checker repeats every 2 m)
    mb.quad(ground, [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]], [0, 1, 0],
            uv0=np.array([[-1.5, -1.5], [1.5, -1.5], [1.5, 1.5], [-1.5, 1.5]]))
    mb.box(red, [0.0, 1.0, -2.5], [5.0, 2.0, 0.3], skip=("-y",))      # back wall
    mb.box(green, [-2.5, 1.0, 0.0], [0.3, 2.0, 4.7], skip=("-y",))    # left wall
    mb.box(gold, [1.2, 0.5, 1.0], [1.2, 1.0, 1.2], skip=("-y",))      # box
    mb.box(slab, [-1.0, 1.4, -1.0], [2.2, 0.15, 2.2])                 # roof slab
    w.node("LightsCourtyard", mesh=w.mesh("LightsCourtyard", mb.build()))
    add_lights(w, [
        ({"name": "Sun", "type": "directional", "color": [1.0, 0.95, 0.85], "intensity": 3.0},
         sun_props([0.5, -1.0, 0.35])),
        ({"name": "Point", "type": "point", "color": [1.0, 0.8, 0.6], "intensity": 4.0},
         {"translation": [1.6, 0.6, -1.6]}),
        ({"name": "Spot", "type": "spot", "color": [0.7, 0.85, 1.0], "intensity": 15.0,
          "spot": {"innerConeAngle": math.radians(25), "outerConeAngle": math.radians(35)}},
         aim([1.8, 2.6, 2.4], [-1.2, 0.0, -0.2])),
    ])
    w.write_gltf(path)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    sky_plane(os.path.join(out, "sky_plane.gltf"))
    sky_courtyard(os.path.join(out, "sky_courtyard.gltf"))
    lights_plane(os.path.join(out, "lights_plane.gltf"))
    lights_courtyard(os.path.join(out, "lights_courtyard.gltf"))


if __name__ == "__main__":
    main()
