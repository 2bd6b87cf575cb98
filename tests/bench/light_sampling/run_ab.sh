#!/usr/bin/env bash
# A/B of light sampling between two luxel builds, interleaved, on one machine:
#   tests/bench/light_sampling/run_ab.sh BEFORE/luxel AFTER/luxel [ROUNDS]
# Direct light from many emitters (the Cornell box with 1,058 emissive
# triangles) and from an HDR sky with a sun (foliage scene), 256², 64 spp;
# prints each bake's summary line and kernel timings of raygen.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$here/../../.."
before="$1" after="$2" rounds="${3:-2}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
python3 "$here/make_many_emitters.py" 23 "$work" >/dev/null
python3 "$here/make_sun_sky_hdr.py" "$work/sky.hdr"
run() {  # tag binary scene args...
  local tag="$1" bin="$2" scene="$3"
  shift 3
  LUXEL_CACHE_DIR="$work/cl-$tag" "$bin" bake "$scene" --local --out "$work/out" \
    --resolution 256 --samples 64 "$@" 2>&1 | grep -E "^(baked|raygen )" | sed "s|^|$tag $(basename "$scene") $* |"
}
for tag in before after; do  # warm the kernel caches
  bin="$before"; [ "$tag" = after ] && bin="$after"
  LUXEL_CACHE_DIR="$work/cl-$tag" "$bin" bake "$work/cornell_many.gltf" --local --out "$work/out" \
    --resolution 32 --samples 1 >/dev/null
  LUXEL_CACHE_DIR="$work/cl-$tag" "$bin" bake "$root/scenes/foliage_instanced.glb" --local \
    --out "$work/out" --resolution 32 --samples 1 --sky-image "$work/sky.hdr" >/dev/null
done
for round in $(seq "$rounds"); do
  for tag in before after; do
    bin="$before"; [ "$tag" = after ] && bin="$after"
    run "$tag" "$bin" "$root/scenes/cornell_box.gltf" --bounces 0
    run "$tag" "$bin" "$work/cornell_many.gltf" --bounces 0
    run "$tag" "$bin" "$root/scenes/foliage_instanced.glb" --bounces 0 --sky-image "$work/sky.hdr"
    run "$tag" "$bin" "$root/scenes/foliage_instanced.glb" --bounces 3 --sky-image "$work/sky.hdr"
  done
done
