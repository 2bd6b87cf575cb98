#!/usr/bin/env bash
# Fails when a C, C++ or OpenCL C source of the project differs from what the
# root .clang-format makes of it (Google style, 100 columns). Lists the files
# and the first differences; fix with `clang-format -i FILE...`.
#   tests/format/check_format.sh [SOURCE_DIR]
# Generated files that say so in their first line are skipped.
set -euo pipefail
root="${1:-$(cd "$(dirname "$0")/../.." && pwd)}"
cd "$root"
formatter="${CLANG_FORMAT:-clang-format}"
command -v "$formatter" > /dev/null || { echo "check_format: $formatter not found" >&2; exit 2; }
if git rev-parse --is-inside-work-tree > /dev/null 2>&1; then
  mapfile -t files < <(git ls-files -- '*.cpp' '*.h' '*.c' '*.cl')
else
  mapfile -t files < <(find server client kernels tests \
    \( -name '*.cpp' -o -name '*.h' -o -name '*.c' -o -name '*.cl' \) -print | sort)
fi
bad=()
checked=0
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  head -n 1 "$f" | grep -q 'GENERATED' && continue
  checked=$((checked + 1))
  if ! "$formatter" --style=file --dry-run --Werror "$f" > /dev/null 2>&1; then
    bad+=("$f")
  fi
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "check_format: ${#bad[@]} of $checked files are not clang-formatted:"
  for f in "${bad[@]}"; do
    echo "  $f"
    "$formatter" --style=file --dry-run "$f" 2>&1 | head -n 6 | sed 's/^/    /'
  done
  exit 1
fi
echo "check_format: $checked files formatted"
