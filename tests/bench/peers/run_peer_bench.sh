#!/usr/bin/env bash
# Luxel vs Blender Cycles, side by side. One command, one machine,
# one run: bakes every scene with Luxel and with each Cycles version, then
# prints the tables.
#
#   tests/bench/peers/install-blender.sh     # once (apt: blender 3.4.1, python3-openimageio;
#                                            # pip: bpy 5.0.1 in ~/.cache/luxel/bpy-5.0.1)
#   tests/bench/peers/run_peer_bench.sh [OUT]   # default OUT = out/peers
#
# PEER_BLENDERS=3.4.1,5.0.1 (the default: every one installed): the Cycles
# versions, each a column of the report. 3.4.1 is Debian's `blender` binary
# (BLENDER=...), 5.0.1 the bpy module in the venv of tests/support/bpy-venv.sh.
#
# Needs a built luxel (build/client/luxel, or set LUXEL=...). About 4.5
# minutes on a 2-core machine for the five 64^2 scenes. PEER_HEAVY=1 adds the gas
# station (/work/shared/scenes/gas_station.glb or PEER_GAS=...; 512^2, 99k
# triangles; about 2.5 minutes more). PEER_ONLY=a,b: only those scenes.
# PEER_QUICK=1: tiny sample counts (a smoke run, ~1 min; its numbers mean
# nothing). On a shared machine prefix with `flock /tmp/luxel-cpu.lock`.
#
# Luxel runs two ladders: its default (luxel/: irradiance_denoised.exr where
# the manifest lists it, the denoiser's seconds charged to it) and
# `--denoise off` (luxel_raw/). The reference and the filter check are raw
# (`--denoise off`). Cycles versions with Open Image Denoise (5.0.1's bpy;
# Debian's 3.4.1 has none) also write each bake denoised (`--denoise oidn`),
# the "Cycles + OIDN" series; every Cycles ladder gets a 64-spp rung (the
# goal figure's target).
set -euo pipefail

HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
OUT=${1:-$ROOT/out/peers}
LUXEL=${LUXEL:-$ROOT/build/client/luxel}
BLENDER=${BLENDER:-blender}
# shellcheck source=tests/support/bpy-venv.sh
source "$ROOT/tests/support/bpy-venv.sh"
BPY_PY="$(bpy_venv_dir)/bin/python"
PY=/usr/bin/python3          # Debian's python: numpy + OpenImageIO bindings
RES=${PEER_RES:-64}
# LUXEL_OPTS="--no-radiance-cache ...": extra options for both Luxel ladders
# (not the reference, which traces every path: the radiance cache is
# consistent but biased at finite samples).
read -r -a luxel_opts <<< "${LUXEL_OPTS:-}"
traced=()
"$LUXEL" bake --help 2>&1 | grep -q -- --no-radiance-cache && traced=(--no-radiance-cache)
BOUNCES=${PEER_BOUNCES:-4}
SKY=0.5,0.8,1.0              # constant sky radiance (W/m^2/sr) of the sky scenes

# the Cycles versions installed: the blender binary's, the bpy venv's
BIN_VERSION=$("$BLENDER" --version 2>/dev/null | head -1 | cut -d' ' -f2 || true)
installed=()
[ -n "$BIN_VERSION" ] && installed+=("$BIN_VERSION")
bpy_venv_ready && [ "$BPY_VERSION" != "$BIN_VERSION" ] && installed+=("$BPY_VERSION")
if [ -n "${PEER_BLENDERS:-}" ]; then
  IFS=',' read -r -a PEERS <<< "$PEER_BLENDERS"
else
  PEERS=("${installed[@]}")
fi
[ ${#PEERS[@]} -gt 0 ] || { echo "run_peer_bench: no Blender; run $HERE/install-blender.sh" >&2; exit 2; }
for v in "${PEERS[@]}"; do
  [[ " ${installed[*]} " == *" $v "* ]] || {
    echo "run_peer_bench: Cycles $v is not installed (have: ${installed[*]:-none}; blender binary" \
         "'$BLENDER', bpy venv $(bpy_venv_dir)); run $HERE/install-blender.sh" >&2; exit 2; }
done
# blender_bake VERSION ARGS...: blender_bake.py under that Cycles version
blender_bake() {
  local v="$1"
  shift
  if [ "$v" = "$BIN_VERSION" ]; then
    "$BLENDER" -b --factory-startup --python "$HERE/blender_bake.py" -- "$@"
  else   # the bpy module: plain python, factory settings reset by the script
    "$BPY_PY" "$HERE/blender_bake.py" "$@"
  fi
}
# cycles_has_oidn VERSION: whether that Blender is built with Open Image
# Denoise (Cycles' _cycles.with_openimagedenoise); blender_bake.py --denoise
# oidn then denoises each bake with Blender's own library
cycles_has_oidn() {
  local v="$1" expr='import bpy, _cycles; print("OIDN", _cycles.with_openimagedenoise)'
  local got
  if [ "$v" = "$BIN_VERSION" ]; then
    got=$("$BLENDER" -b --factory-startup --python-expr "$expr" 2>/dev/null || true)
  else
    got=$("$BPY_PY" -c "$expr" 2>/dev/null || true)
  fi
  [[ "$got" == *"OIDN True"* ]]
}
[ -x "$LUXEL" ] || { echo "run_peer_bench: no luxel at $LUXEL (build first, or set LUXEL)" >&2; exit 2; }
"$PY" -c "import numpy, OpenImageIO" 2>/dev/null || { echo "run_peer_bench: $PY lacks numpy/OpenImageIO; run $HERE/install-blender.sh" >&2; exit 2; }

# name | scene | lightmap side | sky R,G,B | sun X,Y,Z,E,DEG (Luxel --sun, --sun-illuminance,
#   --sun-radius) | angular radius of the glTF's directional lights (deg) | Luxel reference spp |
#   Luxel ladder | Cycles ladder | Cycles converged spp (x2 seeds) |
#   spp of the 4x-resolution filter check (0: none)
SUN_GAS=0.4,-0.8,0.45,3.0,0.27  # gas station: a sun (W/m^2 facing it) ...
SKY_GAS=0.10,0.15,0.25           # ... and a dim blue sky
GAS=${PEER_GAS:-/work/shared/scenes/gas_station.glb}
if [ "${PEER_QUICK:-0}" = 1 ]; then
  SCENES=(
    "sky_plane|@/sky_plane.gltf|$RES|$SKY|||64|||64|0"
    "lights_plane|@/lights_plane.gltf|$RES|||0.27|256|||64|0"
    "cornell_box|$ROOT/scenes/cornell_box.gltf|$RES|||0|256|4,16|4,16|64|0"
    "sky_courtyard|@/sky_courtyard.gltf|$RES|$SKY|||256|4,16|4,16|64|16"
    "lights_courtyard|@/lights_courtyard.gltf|$RES|||0.27|256|4,16|4,16|64|0"
  )
  HEAVY=("gas_station|$GAS|256|$SKY_GAS|$SUN_GAS||64|4,16|1,4|16|0")
else
  SCENES=(
    "sky_plane|@/sky_plane.gltf|$RES|$SKY|||256|||256|0"
    "lights_plane|@/lights_plane.gltf|$RES|||0.27|4096|||1024|0"
    "cornell_box|$ROOT/scenes/cornell_box.gltf|$RES|||0|8192|1,2,4,8,16,32,64,128,256,512,1024|1,2,4,8,16,32,64,128,256,512,1024|4096|0"
    "sky_courtyard|@/sky_courtyard.gltf|$RES|$SKY|||32768|1,2,4,8,16,32,64,128,256,512,1024,2048|1,2,4,8,16,32,64,128,256,512,1024,2048|8192|256"
    "lights_courtyard|@/lights_courtyard.gltf|$RES|||0.27|16384|1,2,4,8,16,32,64,128,256,512,1024|1,2,4,8,16,32,64,128,256,512,1024|4096|0"
  )
  # 512^2, 99k triangles, 1102 meshes, 95 GGX materials: PEER_HEAVY=1 (about 2.5 more minutes)
  HEAVY=("gas_station|$GAS|512|$SKY_GAS|$SUN_GAS||512|4,8,16,32|1,2,4,8,16,32|128|0")
fi
if [ "${PEER_HEAVY:-0}" = 1 ]; then
  [ -f "$GAS" ] || { echo "run_peer_bench: PEER_HEAVY=1 needs $GAS (set PEER_GAS)" >&2; exit 2; }
  SCENES+=("${HEAVY[@]}")
fi
if [ -n "${PEER_ONLY:-}" ]; then   # PEER_ONLY=name1,name2: a subset
  keep=()
  for spec in "${SCENES[@]}"; do
    [[ ",$PEER_ONLY," == *",${spec%%|*},"* ]] && keep+=("$spec")
  done
  SCENES=("${keep[@]}")
fi

now() { date +%s.%N; }
# share of CPU time not idle over one second (other users of the machine
# distort every timing here: the run waits up to 2 minutes for a quiet machine;
# PEER_QUIET_TRIES=N waits at most N seconds, and the busy share is recorded)
cpu_busy() {
  local a b
  read -r -a a < /proc/stat; sleep 1; read -r -a b < /proc/stat
  "$PY" -c "import sys; a=list(map(int,sys.argv[1].split())); b=list(map(int,sys.argv[2].split())); d=[y-x for x,y in zip(a,b)]; print(f'{1-(d[3]+d[4])/max(sum(d),1):.2f}')" "${a[*]:1}" "${b[*]:1}"
}
wait_quiet() {
  local busy i
  for i in $(seq "${PEER_QUIET_TRIES:-60}"); do
    busy=$(cpu_busy)
    "$PY" -c "import sys; sys.exit(0 if float(sys.argv[1]) < 0.15 else 1)" "$busy" && break
    [ "$i" = 1 ] && echo "   (machine busy: $busy of the CPU in use by others; waiting up to ${PEER_QUIET_TRIES:-60} s)"
    sleep 1
  done
  echo "$busy"
}
elapsed() { "$PY" -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.4f}')" "$1" "$2"; }
json_list() { [ -z "$1" ] && echo "[]" || echo "[$1]"; }

declare -A CYCLES_DENOISE   # per version: "oidn" or why not
for v in "${PEERS[@]}"; do
  if cycles_has_oidn "$v"; then
    CYCLES_DENOISE[$v]=oidn
  else
    CYCLES_DENOISE[$v]="none (built without Open Image Denoise: no Cycles + OIDN series)"
    echo "run_peer_bench: Cycles $v has no Open Image Denoise: its ladder is raw only (no Cycles + OIDN series)"
  fi
done

rm -rf "$OUT"
mkdir -p "$OUT/scenes"
"$PY" "$HERE/make_scenes.py" "$OUT/scenes"
{
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "git: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$ROOT" diff --quiet 2>/dev/null || echo -dirty)"
  echo "luxel: $("$LUXEL" --version 2>&1 | head -1)"
  for v in "${PEERS[@]}"; do
    if [ "$v" = "$BIN_VERSION" ]; then
      echo "blender $v: $(command -v "$BLENDER") (binary)"
    else
      echo "blender $v: $BPY_PY (bpy module)"
    fi
  done
  for v in "${PEERS[@]}"; do
    echo "cycles $v denoise: ${CYCLES_DENOISE[$v]}"
  done
  echo "resolution: $RES (unless a scene sets its own), bounces: $BOUNCES"
  echo "opencl: $(clinfo -l 2>/dev/null | tr '\n' ' ' || true)"
  lscpu | head -20
} > "$OUT/machine.txt"
cat "$OUT/machine.txt"

T_ALL=$(now)
for spec in "${SCENES[@]}"; do
  IFS='|' read -r name scene res sky sun dirrad ref_spp lux_ladder bl_ladder bl_hi hires_spp <<< "$spec"
  scene=${scene/#@/$OUT/scenes}
  d="$OUT/$name"
  # the goal figure's target is Cycles' raw error at 64 spp: every Cycles
  # ladder has that rung
  if [ -n "$bl_ladder" ] && [[ ",$bl_ladder," != *",64,"* ]]; then
    bl_ladder=$(tr ',' '\n' <<< "$bl_ladder,64" | sort -n | paste -sd,)
  fi
  mkdir -p "$d/luxel" "$d/luxel_raw"
  # the same lighting for both: skyarg goes to Luxel, blarg to blender_bake.py
  skyarg=()
  blarg=()
  [ -n "$sky" ] && { skyarg+=(--sky "$sky"); blarg+=(--sky "$sky"); }
  if [ -n "$sun" ]; then
    IFS=',' read -r sx sy sz se sr <<< "$sun"
    skyarg+=(--sun "$sx,$sy,$sz" --sun-illuminance "$se" --sun-radius "$sr")
    blarg+=(--sun "$sun")
  fi
  if [ -n "$dirrad" ]; then
    skyarg+=(--directional-radius "$dirrad")
    blarg+=(--directional-radius "$dirrad")
  fi
  busy=$(wait_quiet | tail -1)
  echo "== $name: CPU busy before start: $busy"
  cat > "$d/settings.json" <<EOF
{"name": "$name", "scene": "$scene", "sky": "$sky", "sun": "$sun", "directional_radius": "$dirrad",
 "resolution": $res, "bounces": $BOUNCES,
 "ref_spp": $ref_spp, "luxel_ladder": $(json_list "$lux_ladder"),
 "blender_ladder": $(json_list "$bl_ladder"), "blender_hi": $bl_hi, "cpu_busy_before": $busy,
 "luxel_denoise": "default", "luxel_raw_ladder": "--denoise off", "luxel_opts": "${LUXEL_OPTS:-}"}
EOF
  echo "== $name: Luxel reference ($ref_spp spp, seed 1, --denoise off, every path traced)"
  "$LUXEL" bake "$scene" --local --out "$d/luxel_ref" --resolution "$res" --samples "$ref_spp" \
      --bounces "$BOUNCES" --seed 1 --denoise off "${traced[@]}" "${skyarg[@]}" --quiet | grep -E '^(lightmap|baked)' || true
  # two ladders, seed 2: Luxel as it ships (luxel/: its default denoiser) and
  # raw (luxel_raw/: --denoise off)
  for ladder in luxel luxel_raw; do
    dnarg=()
    [ "$ladder" = luxel_raw ] && dnarg=(--denoise off)
    for spp in ${lux_ladder//,/ }; do
      t0=$(now)
      "$LUXEL" bake "$scene" --local --out "$d/$ladder/s$spp" --resolution "$res" --samples "$spp" \
          --bounces "$BOUNCES" --seed 2 "${dnarg[@]}" "${skyarg[@]}" "${luxel_opts[@]}" --quiet \
          > "$d/$ladder/s$spp.log"
      elapsed "$t0" "$(now)" > "$d/$ladder/s$spp/wall_s.txt"
      echo "   $ladder $spp spp: $(grep '^baked' "$d/$ladder/s$spp.log" | cut -c12-60)$(grep -o 'denoised, [0-9.]* s' "$d/$ladder/s$spp.log" | sed 's/^/ + /') (process $(cat "$d/$ladder/s$spp/wall_s.txt") s)"
    done
  done
  # Cycles: one Blender process per scene and version; the ladder (seed 3)
  # and the converged map (seeds 1 and 2) after a timed warm-up bake.
  runs=""
  for spp in ${bl_ladder//,/ }; do runs="$runs,$spp@3"; done
  runs="${runs#,},$bl_hi@1,$bl_hi@2"
  runs=${runs#,}
  for v in "${PEERS[@]}"; do
    # Cycles + OIDN: each bake also denoised, its seconds apart (versions with OIDN)
    dnarg=()
    [ "${CYCLES_DENOISE[$v]}" = oidn ] && [ -n "$bl_ladder" ] && dnarg=(--denoise oidn)
    echo "== $name: Cycles $v ($runs)${dnarg[*]:+ + OIDN}"
    blender_bake "$v" --scene "$scene" \
        --out "$d/blender-$v" --resolution "$res" --bounces "$BOUNCES" --runs "$runs" --warmup \
        "${dnarg[@]}" "${blarg[@]}" --t0 "$(now)" > "$d/blender-$v.log" 2>&1 \
      || { tail -30 "$d/blender-$v.log" >&2; exit 1; }
    grep '^blender_bake' "$d/blender-$v.log" | sed 's/^/   /'
  done
  if [ "$hires_spp" != 0 ]; then
    # filter check (not timed): both renderers at 4x the resolution, for the
    # texels where the converged maps disagree (compare.py box-filters down)
    hr=$((res * 4))
    echo "== $name: ${hr}^2 filter check ($hires_spp spp each)"
    mkdir -p "$d/hires"
    echo "{\"resolution\": $hr, \"luxel_spp\": $hires_spp, \"blender_spp\": $hires_spp}" > "$d/hires/settings.json"
    "$LUXEL" bake "$scene" --local --out "$d/hires/luxel" --resolution "$hr" --samples "$hires_spp" \
        --bounces "$BOUNCES" --seed 1 --denoise off "${skyarg[@]}" --quiet > "$d/hires/luxel.log"
    for v in "${PEERS[@]}"; do
      blender_bake "$v" --scene "$scene" \
          --out "$d/hires/blender-$v" --resolution "$hr" --bounces "$BOUNCES" --runs "$hires_spp@1" \
          "${blarg[@]}" > "$d/hires/blender-$v.log" 2>&1 || { tail -30 "$d/hires/blender-$v.log" >&2; exit 1; }
    done
  fi
done
echo "== all bakes: $(elapsed "$T_ALL" "$(now)") s"
echo
"$PY" "$HERE/compare.py" "$OUT" | tee "$OUT/report.md"
