#!/usr/bin/python3
"""Opens N header-only uploads (each on its own channel) against a fresh
luxeld and reports the daemon's threads and staging folders 3 s later, and
how the uploads ended by then. Run with a daemon before and after a change
(docs/performance.md, "Stream limits and soak"):

    PYTHONPATH=client/python:BUILD/python /usr/bin/python3 tests/bench/held_uploads.py \\
        --luxeld BUILD/server/service/luxeld [--uploads 60] [-- extra luxeld flags]
"""

import argparse
import collections
import os
import pathlib
import sys
import threading
import time

_REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(_REPO / "client/python"))
sys.path.insert(0, str(_REPO / "tests/python"))

import grpc  # noqa: E402

from luxel_client import luxel_pb2, luxel_pb2_grpc  # noqa: E402
from luxeld_process import Luxeld  # noqa: E402


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxeld", required=True)
    p.add_argument("--uploads", type=int, default=60)
    p.add_argument("extra", nargs="*", help="flags passed to luxeld (after --)")
    args = p.parse_args(argv)
    daemon = Luxeld(args.luxeld, extra_args=args.extra).start()
    pid = daemon.process.pid

    def threads():
        return len(os.listdir(f"/proc/{pid}/task"))

    before = threads()
    release = threading.Event()
    header = luxel_pb2.SceneUploadHeader(name="held.glb", format=luxel_pb2.SCENE_FORMAT_GLB,
                                         total_size=1000, sha256="0" * 64)

    def requests():
        yield luxel_pb2.UploadSceneRequest(header=header)
        release.wait(120)

    channels = [grpc.insecure_channel(daemon.address) for _ in range(args.uploads)]
    futures = [luxel_pb2_grpc.LuxelStub(ch).UploadScene.future(requests()) for ch in channels]
    time.sleep(3)
    ended = collections.Counter()
    for f in futures:
        if f.done():
            try:
                f.result()
                ended["OK"] += 1
            except grpc.RpcError as e:
                ended[e.code().name] += 1
    print(f"{args.uploads} header-only uploads: threads {before} -> {threads()}, staging folders "
          f"{len(os.listdir(daemon.data_dir / 'staging'))}; ended within 3 s: {dict(ended)}")
    release.set()
    for f in futures:
        try:
            f.result(timeout=30)
        except Exception:  # noqa: BLE001 (every outcome is fine here)
            pass
    for ch in channels:
        ch.close()
    daemon.stop()
    daemon.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
