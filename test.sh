#!/usr/bin/env bash
# Installs dependencies, builds Luxel and runs the whole test suite with ctest.
#   ./test.sh              everything (unit, kernel conformance, 60 s fuzzing)
#   ./test.sh --sanitize   the same under ASan + UBSan in build-asan/
# Extra arguments after `--` go to ctest (e.g. ./test.sh -- -R accel).
set -euo pipefail
cd "$(dirname "$0")"
build_dir=build
cmake_args=()
ctest_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --sanitize)
      build_dir=build-asan
      cmake_args+=(-DLUXEL_SANITIZE=ON)
      # PoCL's LLVM keeps compiler state until exit (tests/sanitizers/lsan.supp).
      export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizers/lsan.supp:print_suppressions=0"
      # LeakSanitizer's exit-time tracer occasionally crashes itself ("Tracer
      # caught signal 11", after every test of the binary passed), seen only in
      # processes where PoCL had just compiled a kernel (a cold PoCL cache). A
      # test gets one more run; a real failure fails both.
      ctest_args+=(--repeat until-pass:2)
      shift ;;
    --) shift; break ;;
    *) echo "test.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
./deploy/install-deps.sh
# Third-party readers of the files Luxel writes (Assimp, Blender's glTF
# importer through bpy 5.0.1) and the editor the add-on is tested in.
bpy_python="$(./tests/support/install-test-tools.sh | tail -n 1)"
cmake_args+=(-DLUXEL_BPY_PYTHON="$bpy_python")
./deploy/build.sh "$build_dir" "${cmake_args[@]}"
cd "$build_dir"
ctest --output-on-failure --timeout 900 ${ctest_args[@]+"${ctest_args[@]}"} "$@"
