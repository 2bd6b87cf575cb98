#!/usr/bin/python3
"""Cancel latency in every phase of a bake: starts a fresh luxeld, submits a
large bake (2048^2 with sh2 and sg12 by default), cancels it at several
delays after it turns RUNNING (and once while queued), and reports for each
cancel the phase it hit (read from GetBake just before the call), how long
CancelBake took to return and how long from the call until GetBake showed
CANCELLED (docs/operations.md, "Cancel latency"):

    PYTHONPATH=client/python:BUILD/python /usr/bin/python3 tests/bench/cancel_latency.py \\
        --luxeld BUILD/server/service/luxeld [--resolution 2048] [--encodings sh2,sg12] \\
        [--delays 0,0.1,0.3,0.6,1,1.5,2.5,4,8] [-- extra luxeld flags]

Phases: queued; layout (RUNNING, no lightmap layout reported yet: UV
layout or generation); setup (layout reported, no path traced: sample info,
BVH, buffers, kernels, first tile clear); tracing (paths > 0); finishing (fraction 1: the last iteration done, the
encodings' solve, the denoise and the outputs to come). luxeld is
killed if its resident memory passes --max-rss-gib.
"""

import argparse
import pathlib
import sys
import threading
import time

_REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(_REPO / "client/python"))
sys.path.insert(0, str(_REPO / "tests/python"))

from luxel_client import Client, luxel_pb2  # noqa: E402
from luxeld_process import Luxeld  # noqa: E402

CORNELL = _REPO / "scenes/cornell_box.gltf"
TERMINAL = {"SUCCEEDED", "FAILED", "CANCELLED"}


def state_name(state):
    return luxel_pb2.BakeState.Name(state).replace("BAKE_STATE_", "")


def phase_of(info):
    state = state_name(info.state)
    if state != "RUNNING":
        return state.lower()
    if info.progress.fraction >= 1:
        return "finishing"
    if info.progress.paths > 0:
        return "tracing"
    return "setup" if info.lightmap_layout else "layout"


def rss_watchdog(pid, limit_bytes, stop):
    """Kills the daemon when its resident memory passes the limit."""
    import os
    import signal
    while not stop.is_set():
        try:
            with open(f"/proc/{pid}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:") and int(line.split()[1]) * 1024 > limit_bytes:
                        print(f"luxeld RSS past {limit_bytes / 2**30:.1f} GiB: killed", flush=True)
                        os.kill(pid, signal.SIGKILL)
                        return
        except OSError:
            return
        time.sleep(0.1)


def wait_until(client, bake_id, done, timeout=600.0, period=0.005):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        info = client.get_bake(bake_id)
        if done(info):
            return info
        time.sleep(period)
    raise TimeoutError(f"bake {bake_id}: still {state_name(info.state)}")


def cancel_and_measure(client, bake_id):
    before = client.get_bake(bake_id)
    t0 = time.monotonic()
    reply = client.cancel_bake(bake_id)
    returned = time.monotonic() - t0
    final = wait_until(client, bake_id, lambda b: state_name(b.state) in TERMINAL, period=0.002)
    ended = time.monotonic() - t0
    return phase_of(before), returned, state_name(reply.state), ended, state_name(final.state)


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxeld", required=True)
    p.add_argument("--resolution", type=int, default=2048)
    p.add_argument("--encodings", default="sh2,sg12")
    p.add_argument("--delays", default="0,0.1,0.3,0.6,1,1.5,2.5,4,8")
    p.add_argument("--max-rss-gib", type=float, default=6.0)
    p.add_argument("--denoise", default="atrous", help="denoiser of the finishing-phase bake")
    p.add_argument("extra", nargs="*", help="flags passed to luxeld (after --)")
    args = p.parse_args(argv)
    settings = dict(resolution=args.resolution, samples_per_texel=4096, encodings=args.encodings,
                    progress_interval_s=0.1, snapshot_format="none")
    daemon = Luxeld(args.luxeld, extra_args=["--max-resolution", "8192"] + args.extra).start()
    stop = threading.Event()
    threading.Thread(target=rss_watchdog,
                     args=(daemon.process.pid, args.max_rss_gib * 2**30, stop),
                     daemon=True).start()
    rows = []
    try:
        with Client(daemon.address) as c:
            scene = c.upload_scene(CORNELL)
            # Queued: behind a bake that holds the device.
            blocker = c.submit_bake(scene.scene_id, **settings)
            queued = c.submit_bake(scene.scene_id, **settings)
            rows.append(("queued",) + cancel_and_measure(c, queued.bake_id))
            c.cancel_bake(blocker.bake_id)
            wait_until(c, blocker.bake_id, lambda b: state_name(b.state) in TERMINAL)
            for delay in [float(d) for d in args.delays.split(",")]:
                bake = c.submit_bake(scene.scene_id, **settings)
                wait_until(c, bake.bake_id, lambda b: state_name(b.state) != "QUEUED",
                           period=0.002)
                time.sleep(delay)
                rows.append((f"{delay:g} s",) + cancel_and_measure(c, bake.bake_id))
                print("%-8s phase %-8s call returned %.3f s (%s), call -> end %.3f s (%s)" %
                      rows[-1], flush=True)
            # Finishing: the last iteration done (fraction 1), the solve, the
            # denoise and the outputs still to come.
            finishing = dict(settings, samples_per_texel=8, denoise=args.denoise)
            bake = c.submit_bake(scene.scene_id, **finishing)
            wait_until(c, bake.bake_id, lambda b: b.progress.fraction >= 1 or
                       state_name(b.state) in TERMINAL, period=0.002)
            rows.append(("last iteration done",) + cancel_and_measure(c, bake.bake_id))
            print("%-8s phase %-8s call returned %.3f s (%s), call -> end %.3f s (%s)" %
                  rows[-1], flush=True)
    finally:
        stop.set()
        daemon.stop()
        daemon.cleanup()
    print(f"\n{args.resolution}^2, encodings {args.encodings}")
    print("| cancel at | phase | CancelBake returned | reply | call -> end | end |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %s | %.3f s | %s | %.3f s | %s |" % r)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
