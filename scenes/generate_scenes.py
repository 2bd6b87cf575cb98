#!/usr/bin/env python3
"""Generate the bundled Luxel test scenes.

Writes, next to this script:
  cornell_box.gltf + cornell_box.bin   -- .gltf with an external buffer
  foliage_instanced.glb                -- .glb, embedded PNGs, instancing, lights
  procedural_city.glb                  -- 549,574 world triangles (285,442 unique)

Usage (only /usr/bin/python3 with numpy; stdlib otherwise):
  python3 scenes/generate_scenes.py            # generate all scenes

The code lives in scenes/gen/: gltf_writer.py (the glTF writer), geometry.py
(math helpers, lightmap chart packer, MeshBuilder) and one module per scene.
The files are validated by the importer's tests (tests/unit/scene,
scene_import_test), which load every .gltf/.glb in scenes/.

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
import os
import sys

sys.dont_write_bytecode = True  # do not leave __pycache__ in scenes/

from gen.cornell_box import make_cornell_box  # noqa: E402
from gen.foliage_instanced import make_foliage  # noqa: E402
from gen.procedural_city import make_city  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))

SCENES = [("cornell_box.gltf", make_cornell_box), ("foliage_instanced.glb", make_foliage),
          ("procedural_city.glb", make_city)]


def main(argv):
    if "--check" in argv:
        # The script's own glTF checker was removed: the importer's tests
        # (scene_import_test) load and validate every bundled scene.
        print("generate_scenes.py: --check is gone; run the importer's tests instead:\n"
              "  ctest --test-dir build -R scene_import_test", file=sys.stderr)
        return 2
    # --no-check is accepted (and means nothing now) so older command lines still work.
    for fname, make in SCENES:
        make(os.path.join(HERE, fname))
    for p in [os.path.join(HERE, f) for f, _ in SCENES] + [os.path.join(HERE, "cornell_box.bin")]:
        print("wrote %s (%d bytes)" % (os.path.relpath(p, os.path.dirname(HERE)), os.path.getsize(p)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
