#!/usr/bin/env python3
"""What sharding a bake costs and gains: per shard the network bytes
(accumulators.bin downloaded, scene uploaded), the merge time, the latency
the coordinator adds to previews, and the speedup of 2 workers over 1.

Daemons on loopback, each worker pinned to its own core (taskset) with PoCL
on one thread, so the two workers do not share a core; the coordinator runs
on whatever is left. The one-worker figure is the same bake on one worker's
own engine (no coordinator); the two-worker figure goes through a
coordinator with shards = 2. Both wall times run from SubmitBake to
SUCCEEDED, as a client sees them.

    LUXELD=build/server/service/luxeld LUXEL_CACHE_DIR=build/cl-cache \
    PYTHONPATH=client/python:build/python:tests/python \
    /usr/bin/python3 tests/bench/shard_overhead.py [--resolution 48] [--spp 1024] [--cores 0,1]
"""

import argparse
import os
import pathlib
import platform
import re
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python"))
from luxel_client import Client, state_name  # noqa: E402
from luxeld_process import Luxeld  # noqa: E402

SCENES = pathlib.Path(__file__).resolve().parents[2] / "scenes"


def log_fields(text, event):
    """key=value fields of every `event=<event>` line of a luxeld log."""
    out = []
    for line in text.splitlines():
        if f"event={event} " in line or line.endswith(f"event={event}"):
            out.append(dict(re.findall(r'(\w+)=("[^"]*"|\S+)', line)))
    return out


def timed_bake(client, scene_id, settings):
    t0 = time.monotonic()
    info = client.submit_bake(scene_id, **settings)
    first_snapshot = None
    with client.watch_bake(info.bake_id) as watch:
        for event in watch:
            if event.HasField("snapshot") and first_snapshot is None:
                first_snapshot = time.monotonic() - t0
            if event.final:
                info = event.info
                break
    wall = time.monotonic() - t0
    if state_name(info.state) != "SUCCEEDED":
        raise SystemExit(f"bake ended {state_name(info.state)}: {info.error_message}\n" + "\n".join(info.notes))
    return info, wall, first_snapshot


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=str(SCENES / "cornell_box.gltf"))
    ap.add_argument("--resolution", type=int, default=48)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--cores", default="0,1", help="two cores, one per worker")
    args = ap.parse_args()
    binary = os.environ["LUXELD"]
    cores = args.cores.split(",")
    settings = dict(resolution=args.resolution, samples_per_texel=args.spp, adaptive=False,
                    paths_per_iteration=16384, snapshot_interval_s=0.5, snapshot_format="exr")

    workers = []
    for core in cores:
        d = Luxeld(binary, ["--checkpoint-interval", "0"], env={"POCL_MAX_PTHREAD_COUNT": "1"})
        d.binary_args = ["-c", core, binary]
        start_pinned(d)
        workers.append(d)
    coord = Luxeld(binary, ["--workers", ",".join(w.address for w in workers)])
    coord.start()
    try:
        with Client(workers[0].address) as w0, Client(coord.address) as c:
            sid = c.upload_scene(args.scene).scene_id
            # Warm-up through the coordinator: it uploads the scene to both
            # workers (the upload figure) and both compile their programs.
            timed_bake(c, sid, dict(settings, samples_per_texel=64, shards=2))
            one, t1, snap1 = timed_bake(w0, sid, settings)
            two, t2, snap2 = timed_bake(c, sid, dict(settings, shards=2))
        log = coord.log()
        downloads = log_fields(log, "shard_downloaded")
        merged = log_fields(log, "shards_merged")
        previews = log_fields(log, "shards_watched")
        uploads = log_fields(log, "worker_scene_uploaded")
        model = next((line.split(":", 1)[1].strip() for line in
                      pathlib.Path("/proc/cpuinfo").read_text().splitlines()
                      if line.startswith("model name")), platform.machine())
        print(f"machine: {model}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; "
              f"workers pinned to cores {args.cores}, PoCL 1 thread each")
        print(f"bake: {pathlib.Path(args.scene).name} {args.resolution}^2, {args.spp} spp uniform, "
              f"{one.progress.paths} paths")
        print(f"1 worker (its own engine):  {t1:.2f} s wall, first snapshot {snap1:.2f} s")
        print(f"2 workers (coordinator):    {t2:.2f} s wall, first snapshot {snap2:.2f} s, "
              f"speedup {t1 / t2:.2f}x")
        # The last bake's downloads (the warm-up's came first).
        for d in downloads[-2:]:
            print(f"  shard {d['shard']}: accumulators.bin {int(d['bytes'])} bytes, "
                  f"download {float(d['seconds']) * 1e3:.1f} ms")
        for u in uploads:
            print(f"  scene upload to {u['worker']} (once: content-addressed): {u['bytes']} bytes")
        for m in merged[-1:]:
            print(f"  merge: read {float(m['read_s']) * 1e3:.1f} ms, merge {float(m['merge_s']) * 1e3:.1f} ms, "
                  f"finish (outputs) {float(m['finish_s']) * 1e3:.1f} ms")
        for p in previews[-1:]:
            print(f"  previews merged: {p['previews']}, {p['preview_ms_mean']} ms each (decode + average)")
        same = two.progress.paths == one.progress.paths
        print(f"paths equal: {same}")
    finally:
        for d in [coord, *workers]:
            d.cleanup()


def start_pinned(d):
    """Luxeld.start with taskset in front of the binary."""
    import subprocess
    from luxeld_process import free_loopback_port
    d.address = f"127.0.0.1:{free_loopback_port()}"
    cmd = ["taskset", *d.binary_args, "--listen", d.address, "--data-dir", str(d.data_dir),
           *d.extra_args]
    d._log = open(d.log_path, "wb")
    d.process = subprocess.Popen(cmd, stdout=d._log, stderr=subprocess.STDOUT, env=d.env)
    deadline = time.monotonic() + 60
    with Client(d.address) as probe:
        while True:
            try:
                probe.wait_ready(timeout=1.0)
                return
            except Exception:
                if d.process.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError("worker did not start:\n" + d.log())


if __name__ == "__main__":
    main()
