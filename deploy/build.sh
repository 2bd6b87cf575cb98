#!/usr/bin/env bash
# Configures and builds Luxel with Clang (libFuzzer needs it) into the given
# folder. Usage: deploy/build.sh BUILD_DIR [extra cmake args...]
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${1:-build}"
shift || true
jobs="${LUXEL_JOBS:-2}"
CC="${CC:-clang}" CXX="${CXX:-clang++}" cmake -S . -B "$build_dir" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
cmake --build "$build_dir" -j"$jobs"
