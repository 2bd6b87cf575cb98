#!/usr/bin/env bash
# Luxel vs Blender Cycles, side by side. One command, one machine,
# one run: bakes every scene with both renderers, then prints the tables.
#
#   tests/bench/peers/install-blender.sh     # once (apt: blender, python3-openimageio)
#   tests/bench/peers/run_peer_bench.sh [OUT]   # default OUT = out/peers
#
# Needs a built luxel (build/client/luxel, or set LUXEL=...). About 4 minutes
# on a 2-core machine. PEER_QUICK=1: tiny sample counts (a smoke run, ~20 s;
# its numbers mean nothing).
set -euo pipefail

HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
OUT=${1:-$ROOT/out/peers}
LUXEL=${LUXEL:-$ROOT/build/client/luxel}
BLENDER=${BLENDER:-blender}
PY=/usr/bin/python3          # Debian's python: numpy + OpenImageIO bindings
RES=${PEER_RES:-64}
BOUNCES=${PEER_BOUNCES:-4}
SKY=0.5,0.8,1.0              # constant sky radiance (W/m^2/sr) of the sky scenes

command -v "$BLENDER" >/dev/null || { echo "run_peer_bench: no blender; run $HERE/install-blender.sh" >&2; exit 2; }
[ -x "$LUXEL" ] || { echo "run_peer_bench: no luxel at $LUXEL (build first, or set LUXEL)" >&2; exit 2; }
"$PY" -c "import numpy, OpenImageIO" 2>/dev/null || { echo "run_peer_bench: $PY lacks numpy/OpenImageIO; run $HERE/install-blender.sh" >&2; exit 2; }

# name | scene | sky | Luxel reference spp | Luxel ladder | Cycles ladder |
#   Cycles converged spp (x2 seeds) | spp of the 4x-resolution filter check (0: none)
if [ "${PEER_QUICK:-0}" = 1 ]; then
  SCENES=(
    "sky_plane|@/sky_plane.gltf|$SKY|64|||64|0"
    "cornell_box|$ROOT/scenes/cornell_box.gltf||256|4,16|4,16|64|0"
    "sky_courtyard|@/sky_courtyard.gltf|$SKY|256|4,16|4,16|64|16"
  )
else
  SCENES=(
    "sky_plane|@/sky_plane.gltf|$SKY|256|||256|0"
    "cornell_box|$ROOT/scenes/cornell_box.gltf||8192|4,8,16,32,64,128,256,512,1024|1,2,4,8,16,32,64,128,256,512,1024|4096|0"
    "sky_courtyard|@/sky_courtyard.gltf|$SKY|32768|4,8,16,32,64,128,256,512,1024,2048|1,2,4,8,16,32,64,128,256,512,1024,2048|8192|256"
  )
fi

now() { date +%s.%N; }
# share of CPU time not idle over one second (other users of the machine
# distort every timing here: the run waits up to 2 minutes for a quiet machine)
cpu_busy() {
  local a b
  read -r -a a < /proc/stat; sleep 1; read -r -a b < /proc/stat
  "$PY" -c "import sys; a=list(map(int,sys.argv[1].split())); b=list(map(int,sys.argv[2].split())); d=[y-x for x,y in zip(a,b)]; print(f'{1-(d[3]+d[4])/max(sum(d),1):.2f}')" "${a[*]:1}" "${b[*]:1}"
}
wait_quiet() {
  local busy i
  for i in $(seq 60); do
    busy=$(cpu_busy)
    "$PY" -c "import sys; sys.exit(0 if float(sys.argv[1]) < 0.15 else 1)" "$busy" && break
    [ "$i" = 1 ] && echo "   (machine busy: $busy of the CPU in use by others; waiting up to 2 min)"
    sleep 1
  done
  echo "$busy"
}
elapsed() { "$PY" -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.4f}')" "$1" "$2"; }
json_list() { [ -z "$1" ] && echo "[]" || echo "[$1]"; }

rm -rf "$OUT"
mkdir -p "$OUT/scenes"
"$PY" "$HERE/make_scenes.py" "$OUT/scenes"
{
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "git: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$ROOT" diff --quiet 2>/dev/null || echo -dirty)"
  echo "luxel: $("$LUXEL" --version 2>&1 | head -1)"
  echo "blender: $("$BLENDER" --version 2>/dev/null | head -1)"
  echo "resolution: $RES, bounces: $BOUNCES"
  lscpu | head -20
} > "$OUT/machine.txt"
cat "$OUT/machine.txt"

T_ALL=$(now)
for spec in "${SCENES[@]}"; do
  IFS='|' read -r name scene sky ref_spp lux_ladder bl_ladder bl_hi hires_spp <<< "$spec"
  scene=${scene/#@/$OUT/scenes}
  d="$OUT/$name"
  mkdir -p "$d/luxel"
  skyarg=()
  [ -n "$sky" ] && skyarg=(--sky "$sky")
  busy=$(wait_quiet | tail -1)
  echo "== $name: CPU busy before start: $busy"
  cat > "$d/settings.json" <<EOF
{"name": "$name", "scene": "$scene", "sky": "$sky", "resolution": $RES, "bounces": $BOUNCES,
 "ref_spp": $ref_spp, "luxel_ladder": $(json_list "$lux_ladder"),
 "blender_ladder": $(json_list "$bl_ladder"), "blender_hi": $bl_hi, "cpu_busy_before": $busy}
EOF
  echo "== $name: Luxel reference ($ref_spp spp, seed 1)"
  "$LUXEL" bake "$scene" --local --out "$d/luxel_ref" --resolution "$RES" --samples "$ref_spp" \
      --bounces "$BOUNCES" --seed 1 "${skyarg[@]}" --quiet | grep -E '^(lightmap|baked)' || true
  for spp in ${lux_ladder//,/ }; do
    t0=$(now)
    "$LUXEL" bake "$scene" --local --out "$d/luxel/s$spp" --resolution "$RES" --samples "$spp" \
        --bounces "$BOUNCES" --seed 2 "${skyarg[@]}" --quiet > "$d/luxel/s$spp.log"
    elapsed "$t0" "$(now)" > "$d/luxel/s$spp/wall_s.txt"
    echo "   luxel $spp spp: $(grep '^baked' "$d/luxel/s$spp.log" | cut -c12-60) (process $(cat "$d/luxel/s$spp/wall_s.txt") s)"
  done
  # Cycles: one Blender process per scene; the ladder (seed 3) and the
  # converged map (seeds 1 and 2) after a timed warm-up bake.
  runs=""
  for spp in ${bl_ladder//,/ }; do runs="$runs,$spp@3"; done
  runs="${runs#,},$bl_hi@1,$bl_hi@2"
  runs=${runs#,}
  echo "== $name: Cycles ($runs)"
  "$BLENDER" -b --factory-startup --python "$HERE/blender_bake.py" -- --scene "$scene" \
      --out "$d/blender" --resolution "$RES" --bounces "$BOUNCES" --runs "$runs" --warmup \
      ${sky:+--sky "$sky"} --t0 "$(now)" > "$d/blender.log" 2>&1 \
    || { tail -30 "$d/blender.log" >&2; exit 1; }
  grep '^blender_bake' "$d/blender.log" | sed 's/^/   /'
  if [ "$hires_spp" != 0 ]; then
    # filter check (not timed): both renderers at 4x the resolution, for the
    # texels where the converged maps disagree (compare.py box-filters down)
    hr=$((RES * 4))
    echo "== $name: ${hr}^2 filter check ($hires_spp spp each)"
    mkdir -p "$d/hires"
    echo "{\"resolution\": $hr, \"luxel_spp\": $hires_spp, \"blender_spp\": $hires_spp}" > "$d/hires/settings.json"
    "$LUXEL" bake "$scene" --local --out "$d/hires/luxel" --resolution "$hr" --samples "$hires_spp" \
        --bounces "$BOUNCES" --seed 1 "${skyarg[@]}" --quiet > "$d/hires/luxel.log"
    "$BLENDER" -b --factory-startup --python "$HERE/blender_bake.py" -- --scene "$scene" \
        --out "$d/hires/blender" --resolution "$hr" --bounces "$BOUNCES" --runs "$hires_spp@1" \
        ${sky:+--sky "$sky"} > "$d/hires/blender.log" 2>&1 || { tail -30 "$d/hires/blender.log" >&2; exit 1; }
  fi
done
echo "== all bakes: $(elapsed "$T_ALL" "$(now)") s"
echo
"$PY" "$HERE/compare.py" "$OUT" | tee "$OUT/report.md"
