#!/usr/bin/python3
"""Service benchmark: what luxeld costs on top of an in-process bake.

Measures, in one run, on one daemon started here (loopback, its own data dir):

1. Overhead: the same scene and settings (same seed) baked in-process
   (`luxel bake --local`) and through luxeld (upload, SubmitBake, WatchBake to
   the final event, DownloadResult of manifest.json). Compared: tracing seconds
   (manifest stats.seconds of each), the in-process run's wall time (process
   start to exit) and the service's end-to-end time (SubmitBake to the final
   event; the upload is timed separately). Median of --repeats runs,
   in-process and daemon runs interleaved so machine-load drift hits both.
2. Snapshot latency: every snapshot a watcher receives, with
   snapshot_interval_s = --snapshot-interval: the gaps between receptions, and
   the delay between the image's progress.elapsed_s and its arrival (excess
   over the smallest delay seen in that bake, so the unknown instant tracing
   started cancels; see snapshot_delays()).
3. Watchers: the same bake with 0, 1, 8, 32 watchers (each its own channel,
   reading every PNG snapshot the stream brings), and with one slow watcher
   that sleeps --slow-sleep s after every event; --watch-repeats bakes each.
   The bake's tracing seconds must not grow beyond run-to-run noise (the
   spread of part 1's identical daemon bakes).

Both paths warm the OpenCL program cache first (LUXEL_CACHE_DIR), so neither
pays kernel compilation. The daemon keeps one OpenCL context per worker
between bakes; the in-process CLI creates one per run (part of its wall time).

    PYTHONPATH=client/python:BUILD/python /usr/bin/python3 tests/bench/service_bench.py \
        --luxeld BUILD/server/service/luxeld --luxel BUILD/client/luxel

Exit status 0 when every bake succeeded and the daemon's bakes traced exactly
as many paths as the in-process ones (same seed and settings); the timings
themselves are reported, not asserted (a shared machine is too noisy).
"""

import argparse
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time

_REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(_REPO / "client/python"))
sys.path.insert(0, str(_REPO / "tests/python"))  # luxeld_process: start/stop a real daemon

from luxel_client import Client, LuxelError, state_name  # noqa: E402
from luxeld_process import Luxeld  # noqa: E402


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxeld", required=True, help="the luxeld executable")
    p.add_argument("--luxel", required=True, help="the luxel CLI executable (for --local)")
    p.add_argument("--scene", default=str(_REPO / "scenes/cornell_box.gltf"))
    p.add_argument("--resolution", type=int, default=256, help="lightmap side in texels")
    p.add_argument("--samples", type=int, default=128, help="samples per texel")
    p.add_argument("--bounces", type=int, default=4)
    p.add_argument("--seed", type=int, default=7)
    p.add_argument("--paths-per-iteration", type=int, default=0, help="batch size (0: engine default)")
    p.add_argument("--repeats", type=int, default=3, help="part 1: runs of each path (median reported)")
    p.add_argument("--watch-repeats", type=int, default=1, help="parts 2-3: bakes per watcher count")
    p.add_argument("--watchers", default="0,1,8,32", help="comma-separated watcher counts")
    p.add_argument("--snapshot-interval", type=float, default=0.5, help="seconds, parts 2 and 3")
    p.add_argument("--slow-sleep", type=float, default=2.0, help="seconds the slow watcher sleeps per event")
    p.add_argument("--quick", action="store_true",
                   help="smoke run: tiny bake, 1 repeat, watchers 0,2 (for ctest)")
    args = p.parse_args(argv)
    if args.quick:
        args.resolution, args.samples, args.bounces, args.repeats, args.watch_repeats = 64, 16, 1, 1, 1
        args.paths_per_iteration = 4096  # several iterations, so the snapshot path runs too
        args.watchers, args.snapshot_interval, args.slow_sleep = "0,2", 0.05, 0.2
    args.watcher_counts = [int(n) for n in args.watchers.split(",") if n.strip()]
    return args


def median(xs):
    return statistics.median(xs) if xs else float("nan")


def percentile(xs, q):
    """q-th percentile (0..100), linear interpolation; nan for no data."""
    if not xs:
        return float("nan")
    s = sorted(xs)
    k = (len(s) - 1) * q / 100.0
    lo, hi = int(k), min(int(k) + 1, len(s) - 1)
    return s[lo] + (s[hi] - s[lo]) * (k - lo)


class Bench:
    def __init__(self, args, work):
        self.args = args
        self.work = work
        self.failures = []

    # ---------------------------------------------------------- in-process

    def bake_local(self, samples=None):
        """`luxel bake --local`; returns dict(wall, trace, setup, paths)."""
        a = self.args
        out = pathlib.Path(tempfile.mkdtemp(prefix="local_", dir=self.work))
        cmd = [a.luxel, "bake", a.scene, "--local", "--quiet", "--out", str(out),
               "--resolution", str(a.resolution), "--samples", str(samples or a.samples),
               "--bounces", str(a.bounces), "--seed", str(a.seed), "--filter", "box"]
        if a.paths_per_iteration:
            cmd += ["--paths-per-iteration", str(a.paths_per_iteration)]
        t0 = time.monotonic()
        run = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.monotonic() - t0
        if run.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({run.returncode}):\n{run.stdout}\n{run.stderr}")
        m = re.search(r"baked\s+([\d.]+) s \(\+([\d.]+) s setup\)", run.stdout)
        manifest = json.loads((out / "manifest.json").read_text())
        return {"wall": wall, "trace": manifest["stats"]["seconds"],
                "setup": float(m.group(2)) if m else float("nan"),
                "paths": manifest["stats"]["paths"], "manifest": manifest}

    # ---------------------------------------------------------- daemon

    def settings(self, samples=None, snapshot_interval_s=0.0):
        a = self.args
        return dict(resolution=a.resolution, samples_per_texel=samples or a.samples,
                    max_bounces=a.bounces, seed=a.seed, filter="box",
                    paths_per_iteration=a.paths_per_iteration,
                    snapshot_interval_s=snapshot_interval_s, snapshot_format="png")

    def manifest(self, client, bake_id):
        out = pathlib.Path(tempfile.mkdtemp(prefix="daemon_", dir=self.work))
        return json.loads(client.download(bake_id, "manifest.json", out / "manifest.json")
                          .path.read_text())

    def bake_daemon(self, client, scene_id, samples=None):
        """SubmitBake, WatchBake to the final event; returns dict(e2e, trace, paths, ...)."""
        t0 = time.monotonic()
        job = client.submit_bake(scene_id, **self.settings(samples))
        info = client.wait(job.bake_id)
        e2e = time.monotonic() - t0
        self.check_succeeded(info)
        manifest = self.manifest(client, job.bake_id)
        return {"e2e": e2e, "trace": manifest["stats"]["seconds"], "paths": manifest["stats"]["paths"],
                "daemon_e2e": info.finished_at - info.submitted_at,
                "queue": info.started_at - info.submitted_at, "manifest": manifest}

    def check_succeeded(self, info):
        if state_name(info.state) != "SUCCEEDED":
            self.failures.append(f"bake {info.bake_id} ended {state_name(info.state)}: {info.error_message}")
            raise RuntimeError(self.failures[-1])

    def bake_watched(self, scene_id, watchers, slow=False):
        """One bake with `watchers` normal watchers (and a slow one when
        `slow`), each on its own channel. Completion is learnt from the
        daemon's own finished_at by polling GetBake (no extra stream)."""
        a = self.args
        records = []  # per watcher: list of (recv unix time, snapshot elapsed_s), final recv time
        with Client(self.address) as control:
            job = control.submit_bake(scene_id, **self.settings(snapshot_interval_s=a.snapshot_interval))
            threads = []
            for i in range(watchers + (1 if slow else 0)):
                rec = {"slow": slow and i == watchers, "snaps": [], "final_at": None, "error": None}
                records.append(rec)
                threads.append(threading.Thread(target=self.watch, args=(job.bake_id, rec), daemon=True))
            for t in threads:
                t.start()
            while True:
                info = control.get_bake(job.bake_id)
                if state_name(info.state) in ("SUCCEEDED", "FAILED", "CANCELLED"):
                    break
                time.sleep(0.1)
            for t in threads:
                t.join(timeout=120)
            self.check_succeeded(info)
            for rec in records:
                if rec["error"]:
                    self.failures.append(f"watcher of {job.bake_id}: {rec['error']}")
            manifest = self.manifest(control, job.bake_id)
        return {"trace": manifest["stats"]["seconds"], "paths": manifest["stats"]["paths"],
                "daemon_e2e": info.finished_at - info.submitted_at, "finished_at": info.finished_at,
                "records": records}

    def watch(self, bake_id, rec):
        try:
            with Client(self.address) as c, c.watch_bake(bake_id) as events:
                for event in events:
                    now = time.time()
                    if event.HasField("snapshot") and event.snapshot.data:
                        rec["snaps"].append((now, event.snapshot.progress.elapsed_s))
                    if event.final:
                        rec["final_at"] = now
                        return
                    if rec["slow"]:
                        time.sleep(self.args.slow_sleep)
        except LuxelError as e:
            rec["error"] = str(e)


def snapshot_delays(records):
    """Gaps between consecutive receptions (s), and per-snapshot delay
    (arrival - elapsed_s) minus the smallest such value over the bake: the
    unknown instant tracing began cancels, so this is the delay beyond the
    fastest delivery observed (a lower bound of the true latency)."""
    gaps, offsets = [], []
    for rec in records:
        if rec["slow"]:
            continue
        times = [t for t, _ in rec["snaps"]]
        gaps += [b - a for a, b in zip(times, times[1:])]
        offsets += [t - e for t, e in rec["snaps"]]
    base = min(offsets) if offsets else 0.0
    return gaps, [o - base for o in offsets]


def fmt(x, digits=2):
    return "n/a" if x != x else f"{x:.{digits}f}"


def main(argv=None):
    args = parse_args(argv)
    work = tempfile.TemporaryDirectory(prefix="luxel_service_bench_")
    bench = Bench(args, pathlib.Path(work.name))
    daemon = Luxeld(args.luxeld, ["--max-concurrent-bakes", "1"])
    print(f"machine: {os.cpu_count()} logical CPUs (shared with other users), "
          f"load average at start {os.getloadavg()[0]:.2f}")
    print(f"scene {args.scene}: resolution {args.resolution}, {args.samples} spp, "
          f"{args.bounces} bounces, seed {args.seed}, box filter; repeats {args.repeats} (part 1), {args.watch_repeats} (parts 2-3)\n", flush=True)
    try:
        daemon.start()
        bench.address = daemon.address
        with Client(daemon.address) as client:
            t0 = time.monotonic()
            scene = client.upload_scene(args.scene)
            upload_s = time.monotonic() - t0
            print(f"daemon {daemon.address}, device {client.server_status().device}")
            # Warm-up: program cache and (daemon) worker context; the bakes are not timed.
            bench.bake_local(samples=2)
            bench.bake_daemon(client, scene.scene_id, samples=2)

            local, remote = [], []
            for i in range(args.repeats):
                local.append(bench.bake_local())
                remote.append(bench.bake_daemon(client, scene.scene_id))
                print(f"  run {i + 1}: in-process trace {local[-1]['trace']:.3f} s wall {local[-1]['wall']:.3f} s"
                      f" | daemon trace {remote[-1]['trace']:.3f} s end-to-end {remote[-1]['e2e']:.3f} s",
                      flush=True)
            for l, r in zip(local, remote):
                if l["paths"] != r["paths"]:
                    bench.failures.append(f"paths differ: in-process {l['paths']} vs daemon {r['paths']}")

        watched = {}
        for n in args.watcher_counts:
            watched[n] = [bench.bake_watched(scene.scene_id, n) for _ in range(args.watch_repeats)]
            print(f"  {n} watchers: trace {[round(w['trace'], 3) for w in watched[n]]}", flush=True)
        slow = [bench.bake_watched(scene.scene_id, 1, slow=True) for _ in range(args.watch_repeats)]
        print(f"  1 watcher + 1 slow: trace {[round(w['trace'], 3) for w in slow]}", flush=True)
    except (LuxelError, RuntimeError) as e:
        print(f"error: {e}\n--- luxeld log ---\n{daemon.log()[-4000:]}", file=sys.stderr)
        return 1
    finally:
        daemon.stop()
        daemon.cleanup()
        work.cleanup()

    report(args, upload_s, local, remote, watched, slow)
    print(f"\nload average at end {os.getloadavg()[0]:.2f}")
    for f in bench.failures:
        print(f"FAILED: {f}", file=sys.stderr)
    return 1 if bench.failures else 0


def report(args, upload_s, local, remote, watched, slow):
    lt, lw, ls = (median([r[k] for r in local]) for k in ("trace", "wall", "setup"))
    dt, de, dd = (median([r[k] for r in remote]) for k in ("trace", "e2e", "daemon_e2e"))
    print(f"\n1. Overhead (median of {args.repeats}; upload {upload_s:.3f} s, excluded)")
    print(f"   {'':40s} {'seconds':>8s}")
    print(f"   {'in-process tracing (stats.seconds)':40s} {lt:8.3f}")
    print(f"   {'in-process setup (atlas, BVH, programs)':40s} {ls:8.3f}")
    print(f"   {'in-process wall (luxel bake --local)':40s} {lw:8.3f}")
    print(f"   {'daemon tracing (stats.seconds)':40s} {dt:8.3f}")
    print(f"   {'daemon submit -> final event (client)':40s} {de:8.3f}")
    print(f"   {'daemon submitted_at -> finished_at':40s} {dd:8.3f}")
    print(f"   tracing overhead   (daemon - in-process) / in-process tracing = {100 * (dt - lt) / lt:+.2f} %")
    # Runs alternate in-process / daemon, so each pair saw similar machine load:
    # the median of per-pair ratios is steadier than a ratio of medians.
    pair_trace = median([100 * (r["trace"] - l["trace"]) / l["trace"] for l, r in zip(local, remote)])
    pair_wall = median([100 * (r["e2e"] - l["wall"]) / l["wall"] for l, r in zip(local, remote)])
    print(f"   paired (median of per-run-pair ratios): tracing {pair_trace:+.2f} %, "
          f"submit->final vs in-process wall {pair_wall:+.2f} %")
    total = lt + ls
    print(f"   end-to-end overhead (submit->final - in-process setup+tracing) / in-process setup+tracing"
          f" = {100 * (de - total) / total:+.2f} %  (charges import, output writing and gRPC to the service)")
    print(f"   end-to-end vs in-process wall (process start, OpenCL context, import, outputs) = "
          f"{100 * (de - lw) / lw:+.2f} %")

    print(f"\n2./3. Watchers (snapshot interval {args.snapshot_interval} s, PNG; "
          f"median over {args.watch_repeats} bake(s); delays pooled over all watchers)")
    print(f"   {'watchers':>16s} {'trace s':>8s} {'vs 0':>7s} {'snaps/w':>8s} {'gap med':>8s} "
          f"{'gap p95':>8s} {'delay med':>9s} {'delay p95':>9s}")
    base = median([w["trace"] for w in watched.get(0, [])]) if 0 in watched else float("nan")
    rows = [(str(n), runs) for n, runs in watched.items()] + [("1 + 1 slow", slow)]
    for label, runs in rows:
        trace = median([w["trace"] for w in runs])
        gaps, delays, counts = [], [], []
        for w in runs:
            g, d = snapshot_delays(w["records"])
            gaps += g
            delays += d
            counts += [len(r["snaps"]) for r in w["records"] if not r["slow"]]
        change = f"{100 * (trace - base) / base:+.1f}%" if base == base else "n/a"
        print(f"   {label:>16s} {trace:8.3f} {change:>7s} {fmt(median(counts), 1):>8s} {fmt(median(gaps)):>8s} "
              f"{fmt(percentile(gaps, 95)):>8s} {fmt(median(delays), 3):>9s} {fmt(percentile(delays, 95), 3):>9s}")
    for w in slow:
        r = [r for r in w["records"] if r["slow"]][0]
        late = r["final_at"] - w["finished_at"] if r["final_at"] else float("nan")
        print(f"   slow watcher: {len(r['snaps'])} snapshots received; final event "
              f"{fmt(late)} s after the bake finished (sleeps {args.slow_sleep} s per event)")
    traces = [r["trace"] for r in remote]
    spread = max(traces) - min(traces)
    print(f"   noise: part-1 daemon tracing spread (max - min of {len(traces)} identical bakes) "
          f"{spread:.3f} s = {100 * spread / dt:.1f} %")


if __name__ == "__main__":
    sys.exit(main())
