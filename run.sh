#!/usr/bin/env bash
# Installs dependencies, builds Luxel and runs the main job: a bake of the
# bundled Cornell box (irradiance lightmap, preview, manifest in out/cornell_box).
#   ./run.sh                        bake scenes/cornell_box.gltf
#   ./run.sh scenes/X.glb [opts]    bake another scene (extra args go to `luxel bake`)
set -euo pipefail
cd "$(dirname "$0")"
./deploy/install-deps.sh
./deploy/build.sh build
scene="${1:-scenes/cornell_box.gltf}"
shift || true
name="$(basename "${scene%.*}")"
exec ./build/client/luxel bake "$scene" --local --out "out/$name" --resolution 256 --samples 256 \
  --bounces 4 "$@"
