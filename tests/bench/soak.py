#!/usr/bin/python3
"""Soak: luxeld under a steady mix of bakes, uploads, watchers and cancels.

One daemon on loopback (its own data dir, small stream caps) and, for
--minutes, these client threads at once:

- bakers: upload the Cornell box (already stored after the first time),
  submit a small bake, cancel one bake in four after a short random delay;
- watchers: watch a recent bake to its final event, or hang up early;
- uploaders: upload a fresh variant of the scene (new content, so a full
  import; deleted again afterwards), or a deliberately truncated upload
  (expects DATA_LOSS), or a deliberately idle one (expects DEADLINE_EXCEEDED
  after --upload-idle-timeout; DATA_LOSS if the soak's end closes it first);
  more uploaders than --max-uploads, so some uploads meet the cap
  (RESOURCE_EXHAUSTED).

Asserted (exit status 1 otherwise): every submitted bake reaches a terminal
state; every bake that SUCCEEDED lists its artifacts and its manifest.json
downloads with a matching sha256; a bake ends CANCELLED only if this script
cancelled it, and none ends FAILED; every upload ends OK or with the status
expected for its kind (RESOURCE_EXHAUSTED allowed for any); no staging
folder is left; the daemon's threads do not grow with the load.
Reported: the daemon's RSS, open fds and threads after warm-up and at the
end (all streams closed), and the counts of each outcome.

    PYTHONPATH=client/python:BUILD/python /usr/bin/python3 tests/bench/soak.py \\
        --luxeld BUILD/server/service/luxeld --minutes 5

ctest -L bench runs a 20-second form (bench_soak_smoke).
"""

import argparse
import collections
import json
import os
import pathlib
import random
import shutil
import sys
import tempfile
import threading
import time

_REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(_REPO / "client/python"))
sys.path.insert(0, str(_REPO / "tests/python"))

import grpc  # noqa: E402

from luxel_client import Client, LuxelError, luxel_pb2, luxel_pb2_grpc, state_name  # noqa: E402
from luxeld_process import Luxeld  # noqa: E402

SMALL = dict(resolution=32, samples_per_texel=16, paths_per_iteration=1024,
             snapshot_interval_s=0.1, snapshot_max_side=32)
TERMINAL = {"SUCCEEDED", "FAILED", "CANCELLED"}


def proc_figures(pid):
    """RSS (MiB), open fds, threads and CPU seconds (user + system) of a
    process, from /proc."""
    status = pathlib.Path(f"/proc/{pid}/status").read_text()
    fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
    stat = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    ticks = int(stat[11]) + int(stat[12])  # utime, stime (fields 14, 15)
    return {"rss_mib": round(int(fields["VmRSS"].split()[0]) / 1024, 1),
            "fds": len(os.listdir(f"/proc/{pid}/fd")),
            "threads": int(fields["Threads"]),
            "cpu_s": round(ticks / os.sysconf("SC_CLK_TCK"), 1)}


class Soak:
    def __init__(self, args, workdir):
        self.args = args
        self.workdir = workdir
        self.stop = threading.Event()
        self.lock = threading.Lock()
        self.bakes = {}  # bake id -> cancelled by us
        self.outcomes = collections.Counter()
        self.errors = []
        self.variant = 0
        self.daemon = Luxeld(args.luxeld, extra_args=[
            "--max-uploads", str(args.max_uploads), "--max-uploads-per-client",
            str(args.max_uploads), "--upload-idle-timeout", str(args.idle_timeout),
            "--max-queued", "10000"]).start()
        self.client = Client(self.daemon.address)
        self.scene = self.client.upload_scene(args.scene)

    def error(self, message):
        with self.lock:
            self.errors.append(message)

    def count(self, what):
        with self.lock:
            self.outcomes[what] += 1

    # ------------------------------------------------------------ workers

    def baker(self, rng):
        while not self.stop.is_set():
            try:
                if rng.random() < 0.2:  # a re-upload: already_stored, unless at the cap
                    try:
                        self.client.upload_scene(self.args.scene)
                    except LuxelError as e:
                        if e.code != "RESOURCE_EXHAUSTED":
                            raise
                info = self.client.submit_bake(self.scene.scene_id, seed=rng.randrange(1 << 30),
                                               **SMALL)
            except LuxelError as e:
                self.error(f"baker: {e}")
                continue
            cancel = rng.random() < 0.25
            with self.lock:
                self.bakes[info.bake_id] = cancel
            self.count("bake_submitted")
            if cancel:
                time.sleep(rng.uniform(0, 0.3))
                try:
                    self.client.cancel_bake(info.bake_id)
                    self.count("bake_cancel_sent")
                except LuxelError as e:
                    self.error(f"cancel: {e}")
            time.sleep(rng.uniform(0.1, 0.5))

    def watcher(self, rng):
        while not self.stop.is_set():
            with self.lock:
                ids = list(self.bakes)[-8:]
            if not ids:
                time.sleep(0.1)
                continue
            hang_up = rng.random() < 0.3
            try:
                with self.client.watch_bake(rng.choice(ids)) as watch:
                    for n, event in enumerate(watch):
                        if event.final:
                            self.count("watch_final")
                            time.sleep(rng.uniform(0, 0.2))
                            break
                        if hang_up and n >= 2:
                            self.count("watch_hung_up")
                            break
            except LuxelError as e:
                self.count(f"watch_{e.code}")
                if e.code != "RESOURCE_EXHAUSTED":
                    self.error(f"watcher: {e}")

    def uploader(self, rng, client, stub, variant_dir):
        while not self.stop.is_set():
            kind = rng.choice(["fresh", "fresh", "truncated", "idle"])
            expected = {"fresh": "OK", "truncated": "DATA_LOSS", "idle": "DEADLINE_EXCEEDED"}[kind]
            code = self.upload_once(kind, client, stub, variant_dir)
            if kind == "idle" and code == "DATA_LOSS" and self.stop.is_set():
                kind, expected = "idle_ended_by_stop", "DATA_LOSS"  # the stream closed early
            self.count(f"upload_{kind}_{code}")
            if code not in (expected, "RESOURCE_EXHAUSTED"):
                self.error(f"{kind} upload ended {code}, expected {expected}")
            if code == "RESOURCE_EXHAUSTED":
                time.sleep(0.2)

    def upload_once(self, kind, client, stub, variant_dir):
        with self.lock:
            self.variant += 1
            n = self.variant
        if kind == "fresh":
            # New content (an `extras` member) so the daemon imports it in full.
            gltf = json.loads(pathlib.Path(self.args.scene).read_text())
            gltf.setdefault("asset", {})["extras"] = {"soak_variant": n}
            path = variant_dir / "variant.gltf"
            path.write_text(json.dumps(gltf))
            try:
                info = client.upload_scene(path)
                client.delete_scene(info.scene_id)
                return "OK"
            except LuxelError as e:
                return e.code
        header = luxel_pb2.SceneUploadHeader(name=f"broken{n}.glb", format=luxel_pb2.SCENE_FORMAT_GLB,
                                             total_size=4096, sha256="0" * 64)

        def requests():
            yield luxel_pb2.UploadSceneRequest(header=header)
            if kind == "truncated":
                yield luxel_pb2.UploadSceneRequest(chunk=b"x" * 1000)
            else:
                self.stop.wait(self.args.idle_timeout * 3)

        try:
            stub.UploadScene(requests(), timeout=self.args.idle_timeout * 10)
            return "OK"
        except grpc.RpcError as e:
            return e.code().name

    # ------------------------------------------------------------ checks

    def check_bakes(self):
        deadline = time.monotonic() + 300
        for bake_id, cancelled in list(self.bakes.items()):
            while True:
                info = self.client.get_bake(bake_id)
                state = state_name(info.state)
                if state in TERMINAL or time.monotonic() > deadline:
                    break
                time.sleep(0.2)
            self.count(f"bake_{state}")
            if state not in TERMINAL:
                self.error(f"bake {bake_id} still {state}")
            elif state == "FAILED":
                self.error(f"bake {bake_id} FAILED: {info.error_message}")
            elif state == "CANCELLED" and not cancelled:
                self.error(f"bake {bake_id} CANCELLED without a CancelBake")
            elif state == "SUCCEEDED":
                missing = {"irradiance.exr", "preview.png", "manifest.json"} - set(info.artifacts)
                if missing:
                    self.error(f"bake {bake_id} SUCCEEDED without {sorted(missing)}")
                else:
                    self.client.download(bake_id, "manifest.json", self.workdir / f"{bake_id}.json")

    def run(self):
        args = self.args
        # Warm-up: one bake through (kernel compiled), then the first figures.
        first = self.client.submit_bake(self.scene.scene_id, **SMALL)
        self.client.wait(first.bake_id)
        pid = self.daemon.process.pid
        before = proc_figures(pid)
        threads = []
        for i in range(args.bakers):
            threads.append(threading.Thread(target=self.baker, args=(random.Random(i),)))
        for i in range(args.watchers):
            threads.append(threading.Thread(target=self.watcher, args=(random.Random(100 + i),)))
        for i in range(args.uploaders):
            d = self.workdir / f"up{i}"
            d.mkdir()
            shutil.copy(pathlib.Path(args.scene).with_suffix(".bin"), d)
            channel = grpc.insecure_channel(self.daemon.address)
            threads.append(threading.Thread(target=self.uploader, args=(
                random.Random(200 + i), Client(self.daemon.address),
                luxel_pb2_grpc.LuxelStub(channel), d)))
        start = time.monotonic()
        for t in threads:
            t.start()
        peak = {k: v for k, v in before.items() if k != "cpu_s"}
        while time.monotonic() - start < args.minutes * 60:
            time.sleep(1)
            now = proc_figures(pid)
            peak = {k: max(peak[k], now[k]) for k in peak if k != "cpu_s"}
        self.stop.set()
        for t in threads:
            t.join()
        self.check_bakes()
        time.sleep(2)  # streams closed, slots freed
        after = proc_figures(pid)
        staging = list((self.daemon.data_dir / "staging").iterdir())
        if staging:
            self.error(f"staging folders left: {staging}")
        if after["threads"] > before["threads"] + 8:
            self.error(f"threads grew from {before['threads']} to {after['threads']}")
        status = self.client.server_status()
        if status.uploads or status.watchers or status.downloads:
            self.error(f"streams still open: {status.uploads} uploads, {status.watchers} "
                       f"watchers, {status.downloads} downloads")
        report = {"minutes": args.minutes, "before": before, "peak": peak, "after": after,
                  "outcomes": dict(sorted(self.outcomes.items())), "errors": self.errors[:20]}
        print(json.dumps(report, indent=1))
        return 0 if not self.errors else 1


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxeld", required=True)
    p.add_argument("--scene", default=str(_REPO / "scenes/cornell_box.gltf"))
    p.add_argument("--minutes", type=float, default=5)
    p.add_argument("--bakers", type=int, default=2)
    p.add_argument("--watchers", type=int, default=12)
    p.add_argument("--uploaders", type=int, default=4)
    p.add_argument("--max-uploads", type=int, default=3, help="the daemon's upload cap")
    p.add_argument("--idle-timeout", type=float, default=2.0, help="--upload-idle-timeout, s")
    p.add_argument("--quick", action="store_true", help="20-second smoke form (ctest -L bench)")
    args = p.parse_args(argv)
    if args.quick:
        args.minutes = 20 / 60
    with tempfile.TemporaryDirectory(prefix="luxel_soak_") as tmp:
        soak = Soak(args, pathlib.Path(tmp))
        try:
            return soak.run()
        finally:
            soak.client.close()
            soak.daemon.stop()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
