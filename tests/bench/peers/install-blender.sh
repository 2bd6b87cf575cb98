#!/usr/bin/env bash
# Installs the optional peer renderer for tests/bench/peers/: Debian's Blender
# (Cycles, CPU device, run headless) and the Python EXR reader the comparison
# uses. NOT part of deploy/install-deps.sh: Blender is large and is only needed
# for the side-by-side benchmark, never by the build or the default tests.
# Idempotent: packages already present are skipped; `apt-get update` runs only
# when something is missing (and at most once).
set -euo pipefail

PACKAGES=(
  blender             # Debian 12: 3.4.1 (Cycles CPU)
  python3-numpy       # compare.py
  python3-openimageio # compare.py reads EXRs with OpenImageIO's Python bindings
)

# shellcheck source=deploy/apt-install.sh
source "$(dirname "$0")/../../../deploy/apt-install.sh"
apt_install_missing install-blender "${PACKAGES[@]}"
