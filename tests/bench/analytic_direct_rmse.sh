#!/bin/bash
# Equal-sample RMSE of --direct analytic against --direct sampled
# (docs/accuracy.md "Analytic direct light"). Usage, from the build folder:
#   ../tests/bench/analytic_direct_rmse.sh SCENE OUTDIR [extra luxel bake options]
# Bakes an 8192-spp --direct sampled reference (seed 1001), then both modes at
# 4..256 spp (seed 1) with --reference, and prints per bake the last line of
# error_series.csv (elapsed_s, paths, mean_spp, min_spp, rel_error, rmse,
# rel_mse), user and sys CPU seconds, and the raygen and total kernel times (ms).
set -euo pipefail
scene=$1
out=$2
shift 2
mkdir -p "$out"
./client/luxel bake "$scene" --local --out "$out/ref" --resolution 64 --samples 8192 \
  --direct sampled --seed 1001 "$@" > "$out/ref.log" 2>&1
for spp in 4 16 64 256; do
  for d in analytic sampled; do
    o="$out/${d}_${spp}"
    /usr/bin/time -o "$o.time" -f "%U %S" ./client/luxel bake "$scene" --local --out "$o" \
      --resolution 64 --samples "$spp" --direct "$d" --seed 1 \
      --reference "$out/ref/irradiance.exr" "$@" > "$o.log" 2>&1
    echo "$d $spp $(tail -1 "$o/error_series.csv") cpu $(cat "$o.time")" \
      "raygen_ms $(awk '/^raygen /{print $3}' "$o.log")" \
      "kernel_ms $(awk '/^total /{print $2}' "$o.log")"
  done
done
