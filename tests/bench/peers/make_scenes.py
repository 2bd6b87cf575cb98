#!/usr/bin/env python3
"""Write the peer-comparison scenes (deterministic; numpy + stdlib only).

  python3 tests/bench/peers/make_scenes.py OUTDIR

writes OUTDIR/sky_plane.gltf (calibration) and OUTDIR/sky_courtyard.gltf.
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
Every material is metallic 0, roughness 1 (Luxel: exact Lambert) and one-sided;
all surfaces are closed boxes (bottom faces on the ground left out) or the
ground quad, so no back face is ever lit.
"""
import functools
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True  # do not leave __pycache__ in scenes/
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "scenes"))
from gen import geometry  # noqa: E402
from gen.gltf_writer import GltfWriter  # noqa: E402

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


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    sky_plane(os.path.join(out, "sky_plane.gltf"))
    sky_courtyard(os.path.join(out, "sky_courtyard.gltf"))


if __name__ == "__main__":
    main()
