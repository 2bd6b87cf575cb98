# shellcheck shell=bash
# Sourced by tests/support/install-test-tools.sh (the round-trip and add-on
# tests), tests/bench/peers/install-blender.sh and run_peer_bench.sh (the
# second Cycles peer): one venv holding Blender as the `bpy` module from PyPI
# (the newest for Python 3.11), kept outside the clone at
#   ${LUXEL_TOOLS_DIR:-${XDG_CACHE_HOME:-~/.cache}/luxel}/bpy-$BPY_VERSION
# so that every user of it finds the same one and it is installed once.
#   bpy_venv_dir       prints that path (the venv's python is bin/python)
#   bpy_venv_ready     true when the venv's bpy is BPY_VERSION
#   bpy_venv_install   installs it unless ready (pip, about 370 MB); needs
#                      BPY_APT_PACKAGES installed first; logs to stderr
BPY_VERSION=5.0.1
# shellcheck disable=SC2034  # used by the scripts that source this file
BPY_APT_PACKAGES=(
  # Debian's python3.11 with venv/ensurepip
  python3 python3-venv
  # shared libraries bpy 5.0.1's __init__.so links (ldd; X11 client
  # libraries only, no display is opened in background mode)
  libx11-6 libxrender1 libxfixes3 libxi6 libxkbcommon0 libxext6 libsm6 libice6 libgl1
)

bpy_venv_dir() {
  echo "${LUXEL_TOOLS_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/luxel}/bpy-$BPY_VERSION"
}

bpy_venv_ready() {
  "$(bpy_venv_dir)/bin/python" -c \
    "import bpy, sys; sys.exit(bpy.app.version_string != '$BPY_VERSION')" >/dev/null 2>&1
}

bpy_venv_install() {
  local venv
  venv="$(bpy_venv_dir)"
  bpy_venv_ready && return 0
  echo "bpy-venv: installing bpy==$BPY_VERSION into $venv (about 370 MB)" >&2
  rm -rf "$venv"
  /usr/bin/python3.11 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check "bpy==$BPY_VERSION" >&2
  "$venv/bin/python" -c "import bpy; print('bpy-venv: bpy', bpy.app.version_string)" >&2
}
