#!/bin/bash
# Sizing figures of docs/operations.md ("Capacity"): luxeld's RSS idle and while
# baking Sponza at 1024^2 through the CLI (peak from /usr/bin/time -v and
# /proc/PID/status sampled every 0.5 s), then the time a busy daemon takes to
# stop on SIGTERM (checkpoint included). Not part of the test suite (minutes).
# usage: tests/deploy/measure_luxeld_rss.sh   (BUILD, SCENES, WORK override paths)
set -u
B=${BUILD:-$(cd "$(dirname "$0")/../.." && pwd)/build}
SCENES=${SCENES:-$(cd "$(dirname "$0")/../../.." && pwd)/shared/scenes}
D=${WORK:-/tmp/luxeld-rss}; rm -rf "$D"; mkdir -p "$D"
export LUXEL_CACHE_DIR=$B/cl-cache
PORT=50977
/usr/bin/time -v -o $D/time.txt $B/server/service/luxeld --data-dir $D/data --listen 127.0.0.1:$PORT 2> $D/luxeld.log &
sleep 1
PID=$(pgrep -P $! luxeld)
for _ in $(seq 60); do $B/client/luxel health --server 127.0.0.1:$PORT >/dev/null 2>&1 && break; sleep 0.5; done
grep VmRSS /proc/$PID/status | sed 's/^/idle /'
( while kill -0 $PID 2>/dev/null; do grep -E "VmRSS" /proc/$PID/status | awk '{print $2}' >> $D/rss.txt; sleep 0.5; done ) &
/usr/bin/time -f "client %e s" $B/client/luxel bake $SCENES/sponza.glb --server 127.0.0.1:$PORT \
  --out $D/out --resolution 1024 --bounces 3 --time 45 --sun 0.2,-1,0.3 --sun-illuminance 20 --sky 0.5,0.6,0.8 2>&1 | tail -5
grep -o '"paths[^,]*' $D/out/manifest.json | head -3
grep VmHWM /proc/$PID/status
# second bake: SIGTERM while it runs
ID=$($B/client/luxel bake $SCENES/sponza.glb --server 127.0.0.1:$PORT --out $D/out2 --resolution 1024 --bounces 3 --time 300 --sun 0.2,-1,0.3 --sun-illuminance 20 --sky 0.5,0.6,0.8 --detach 2>&1 | tail -1)
echo "second: $ID"
sleep 25
T0=$(date +%s.%N); kill -TERM $PID; while kill -0 $PID 2>/dev/null; do sleep 0.05; done; T1=$(date +%s.%N)
echo "stop_s $(echo "$T1 - $T0" | bc)"
sleep 1
grep -E "Maximum resident|User time|System time|Elapsed" $D/time.txt
sort -n $D/rss.txt | tail -1 | sed 's/^/max sampled VmRSS kB /'
grep -E "shutdown_requested|checkpoint_written|bake_interrupted|stopped" $D/luxeld.log | tail -4
ls -la $D/data/bakes/*/checkpoint.bin 2>/dev/null
