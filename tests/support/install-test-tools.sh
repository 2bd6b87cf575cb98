#!/usr/bin/env bash
# Installs the third-party readers the test suite checks Luxel's written files
# with, and the editor the Blender add-on is tested in. Called by ./test.sh
# after deploy/install-deps.sh; NOT part of deploy/install-deps.sh, because
# a deployment never needs them.
#   - Assimp from Debian (assimp-utils: the `assimp` command; libassimp-dev
#     for tests/roundtrip/assimp_dump.cpp, which reads every UV set of every
#     mesh: pyassimp 5.2 crashes on load, and `assimp export -fassjson`
#     asserts on glTF extras).
#   - Blender 5.0.1 as the `bpy` module from PyPI (the newest for Python
#     3.11), in a venv kept outside the clone:
#     ${LUXEL_TOOLS_DIR:-~/.cache/luxel}/bpy-5.0.1 (tests/support/bpy-venv.sh,
#     shared with tests/bench/peers/install-blender.sh). Its glTF importer and
#     exporter (io_scene_gltf2, with the Draco encoder) ship inside the wheel.
#   - numpy and OpenImageIO's Python module from Debian, for the benches.
#   - gltfpack 1.2 (meshoptimizer's glTF packer), an independent writer of
#     EXT_meshopt_compression: the executable inside PyPI's
#     dsts-extractor-gltfpack 1.2.0 wheel. The wheel asks for Python 3.12 and
#     the venv has 3.11, so pip downloads it for 3.12 and only the executable
#     (which needs no Python) is unpacked, to
#     ${LUXEL_TOOLS_DIR:-~/.cache/luxel}/gltfpack-1.2.0/gltfpack, where the
#     tests' CMake looks for it beside the bpy venv.
# Idempotent: apt runs only for what is missing, pip only when the venv lacks
# bpy 5.0.1. Prints the venv's python as its last line.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"

PACKAGES=(
  assimp-utils libassimp-dev
  # The benches under tests/bench/ read EXRs in Python (error_vs_time.py,
  # equal_error.py, radiance_cache_bias.py).
  python3-numpy python3-openimageio
)
# shellcheck source=tests/support/bpy-venv.sh
source "$here/bpy-venv.sh"
# shellcheck source=deploy/apt-install.sh
source "$here/../../deploy/apt-install.sh"
apt_install_missing install-test-tools "${PACKAGES[@]}" "${BPY_APT_PACKAGES[@]}" >&2

bpy_venv_install
venv="$(bpy_venv_dir)"
GLTFPACK_VERSION=1.2.0
gltfpack="$(dirname "$venv")/gltfpack-$GLTFPACK_VERSION/gltfpack"
if ! "$gltfpack" -v 2>/dev/null | grep -q '^gltfpack'; then
  echo "install-test-tools: installing gltfpack $GLTFPACK_VERSION into $(dirname "$gltfpack")" >&2
  wheels="$(mktemp -d)"
  "$venv/bin/pip" download --quiet --disable-pip-version-check --no-deps --only-binary=:all: \
    --python-version 3.12 -d "$wheels" "dsts-extractor-gltfpack==$GLTFPACK_VERSION" >&2
  mkdir -p "$(dirname "$gltfpack")"
  "$venv/bin/python" - "$wheels" "$gltfpack" <<'PY'
import glob, sys, zipfile
wheel = glob.glob(sys.argv[1] + "/*.whl")[0]
with zipfile.ZipFile(wheel) as z, open(sys.argv[2], "wb") as out:
    out.write(z.read("dsts_extractor_gltfpack/_binary/gltfpack"))
PY
  chmod +x "$gltfpack"
  rm -rf "$wheels"
  "$gltfpack" -v >&2
fi
echo "$venv/bin/python"
