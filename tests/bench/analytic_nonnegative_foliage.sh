#!/bin/bash
# Equal-sample RMSE of direct = auto before and after the non-negative
# analytic estimator (docs/accuracy.md "Analytic direct light"): a delta sun
# and a constant sky over the bundled foliage scene (its own point, spot and
# directional lights too), 64^2, 2 bounces, against a 4096-spp --direct
# sampled reference (seed 1001). OLD_KERNEL_DIR: the previous kernels/
# (git archive COMMIT kernels | tar -x), run through LUXEL_KERNEL_DIR.
# Prints mode, spp, the last line of error_series.csv and the channel minima.
set -e
usage="usage: analytic_nonnegative_foliage.sh OUTDIR OLD_KERNEL_DIR"
mkdir -p "${1:?$usage}"
O=$(cd "$1" && pwd)
OLDK=$(cd "${2:?$usage}" && pwd)
cd "$(dirname "$0")/../../build"
S=../scenes/foliage_instanced.glb
L="--sky 0.4,0.5,0.7 --sun 0.3,-1,0.2 --sun-illuminance 5 --sun-radius 0 --resolution 64 --bounces 2"
[ -f $O/ref/irradiance.exr ] || ./client/luxel bake $S --local --out $O/ref --samples 4096 --direct sampled --seed 1001 $L > $O/ref.log 2>&1
for spp in 16 64 256; do
  for mode in old new sampled; do
    o=$O/${mode}_$spp
    d=auto; [ $mode = sampled ] && d=sampled
    if [ $mode = old ]; then export LUXEL_KERNEL_DIR=$OLDK; else unset LUXEL_KERNEL_DIR; fi
    ./client/luxel bake $S --local --out $o --samples $spp --direct $d --seed 1 --reference $O/ref/irradiance.exr $L > $o.log 2>&1
    echo "$mode $spp $(tail -1 $o/error_series.csv) | $(oiiotool --stats $o/irradiance.exr | grep "Stats Min")"
  done
done
