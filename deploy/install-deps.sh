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
  # `luxel report --plot` and the benchmark suite's plots
  python3-matplotlib
)

# shellcheck source=deploy/apt-install.sh
source "$(dirname "$0")/apt-install.sh"
apt_install_missing install-deps "${PACKAGES[@]}"
