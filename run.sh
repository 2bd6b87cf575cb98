#!/usr/bin/env bash
# Installs dependencies, builds Luxel and runs the main job on a bundled scene.
#   ./run.sh                   inspect scenes/cornell_box.gltf
#   ./run.sh scenes/X.glb ...  inspect another scene (extra args go to `luxel inspect`)
set -euo pipefail
cd "$(dirname "$0")"
./deploy/install-deps.sh
./deploy/build.sh build
scene="${1:-scenes/cornell_box.gltf}"
shift || true
exec ./build/client/luxel inspect "$scene" "$@"
