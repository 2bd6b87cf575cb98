#!/usr/bin/env bash
# Installs dependencies, builds Luxel and runs the main job: starts the luxeld
# daemon on loopback, bakes the bundled Cornell box through it with
# `luxel bake` (upload, submit, watch with a progress bar, download), writes
# the results to out/cornell_box/ and stops the daemon.
#   ./run.sh                        bake scenes/cornell_box.gltf
#   ./run.sh scenes/X.glb [opts]    bake another scene (extra args go to `luxel bake`)
# The daemon's data (scenes, bakes, results) stays in out/luxeld-data/.
set -euo pipefail
cd "$(dirname "$0")"
./deploy/install-deps.sh
./deploy/build.sh build
scene="${1:-scenes/cornell_box.gltf}"
shift || true
name="$(basename "${scene%.*}")"
port="${LUXEL_PORT:-50151}"
mkdir -p out
./build/server/service/luxeld --listen "127.0.0.1:$port" --data-dir out/luxeld-data \
  2> out/luxeld.log &
daemon=$!
stop_daemon() { kill -TERM "$daemon" 2>/dev/null && wait "$daemon" 2>/dev/null || true; }
trap stop_daemon EXIT
# Wait until the daemon answers (it binds before it accepts; a few seconds at most).
for _ in $(seq 1 60); do
  kill -0 "$daemon" 2>/dev/null || { echo "luxeld exited; see out/luxeld.log" >&2; cat out/luxeld.log >&2; exit 1; }
  ./build/client/luxel list --server "127.0.0.1:$port" --timeout 1 > /dev/null 2>&1 && break
  sleep 0.5
done
status=0
./build/client/luxel bake "$scene" --server "127.0.0.1:$port" --out "out/$name" \
  --resolution 256 --samples 256 --bounces 4 "$@" || status=$?
echo "daemon log: out/luxeld.log"
exit "$status"
