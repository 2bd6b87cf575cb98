#!/usr/bin/env bash
# Installs the optional peer renderers for tests/bench/peers/, both Blender
# Cycles (CPU device, run headless):
#   - Debian's Blender 3.4.1 (the `blender` command, apt);
#   - Blender 5.0.1 as the `bpy` module from PyPI, in the venv the test suite
#     uses (tests/support/bpy-venv.sh: ~/.cache/luxel/bpy-5.0.1, outside the
#     clone; installed once for both);
# and the Python EXR reader the comparison uses. NOT part of
# deploy/install-deps.sh: Blender is large and is only needed for the
# side-by-side benchmark, never by the build or the default tests.
# Idempotent: packages already present are skipped; `apt-get update` runs only
# when something is missing (and at most once); pip only when the venv lacks
# bpy 5.0.1.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"

PACKAGES=(
  blender             # Debian 12: 3.4.1 (Cycles CPU)
  python3-numpy       # compare.py
  python3-openimageio # compare.py reads EXRs with OpenImageIO's Python bindings
)

# shellcheck source=tests/support/bpy-venv.sh
source "$here/../../support/bpy-venv.sh"
# shellcheck source=deploy/apt-install.sh
source "$here/../../../deploy/apt-install.sh"
apt_install_missing install-blender "${PACKAGES[@]}" "${BPY_APT_PACKAGES[@]}"
bpy_venv_install
echo "install-blender: blender $(blender --version 2>/dev/null | head -1 | cut -d' ' -f2), bpy $BPY_VERSION in $(bpy_venv_dir)"
