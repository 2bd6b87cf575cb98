#!/usr/bin/env bash
# Installs every Debian package Luxel's build, tests and tools need.
# Idempotent: packages already present are skipped; `apt-get update` runs only
# when something is missing (and at most once).
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake pkg-config git clang libclang-rt-dev clang-format
  # OpenCL: headers (C and C++), ICD loader, PoCL CPU driver
  opencl-headers opencl-clhpp-headers ocl-icd-opencl-dev pocl-opencl-icd clinfo
  # geometry and images
  libembree-dev libopenimageio-dev openimageio-tools
  libtinygltf-dev nlohmann-json3-dev libstb-dev
  # compressed glTF geometry: KHR_draco_mesh_compression (Draco decoder) and
  # EXT_meshopt_compression (meshoptimizer), scene/gltf_decompress.cpp
  libdraco-dev libmeshoptimizer-dev
  # lightmap UV generation: sparse least squares for LSCM (uv/)
  libeigen3-dev
  # service: gRPC + protobuf (C++ and Python), OpenSSL for SHA-256 and TLS
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc libssl-dev
  python3-grpcio python3-protobuf
  # luxeld --metrics-listen: Prometheus client (registry + pull exposer)
  prometheus-cpp-dev
  # tests
  googletest libgtest-dev libgmock-dev
  python3 python3-numpy
  # pip, for Open Image Denoise's official libraries (below)
  python3-pip
  # `luxel report --plot` and the benchmark suite's plots
  python3-matplotlib
)

# shellcheck source=deploy/apt-install.sh
source "$(dirname "$0")/apt-install.sh"
apt_install_missing install-deps "${PACKAGES[@]}"

# Intel Open Image Denoise 2.5.1 (`--denoise oidn`, post/oidn.h): Debian 12 has
# no package, so the official libraries come from the PyPI wheel pyoidn, which
# ships them (libOpenImageDenoise.so.2, the core with the trained weights, the
# CPU device, TBB) under pyoidn/oidn/lib. Installed into a prefix Luxel owns,
# never into the system's Python; Luxel dlopens it from there at run time
# (LUXEL_OIDN_LIBRARY overrides). --no-deps: only the libraries are wanted.
# PIP_BREAK_SYSTEM_PACKAGES: Debian's pip refuses even a --target install
# into a Python it calls externally managed; older pips ignore the variable.
# LUXEL_WITH_OIDN=0 skips it (the container image: Debian packages only, and
# its bakes fall back to the a-trous filter).
oidn_prefix="${LUXEL_PREFIX:-/opt/luxel}/oidn"
oidn_lib="$oidn_prefix/pyoidn/oidn/lib/libOpenImageDenoise.so.2"
if [ "${LUXEL_WITH_OIDN:-1}" = "0" ]; then
  echo "install-deps: Open Image Denoise skipped (LUXEL_WITH_OIDN=0)"
elif [ -e "$oidn_lib" ]; then
  echo "install-deps: Open Image Denoise present ($oidn_lib)"
else
  echo "install-deps: installing Open Image Denoise 2.5.1 into $oidn_prefix"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo env PIP_BREAK_SYSTEM_PACKAGES=1 python3 -m pip install --quiet --no-deps \
    --upgrade --target "$oidn_prefix" pyoidn==2.5.1.0
  test -e "$oidn_lib"
fi
