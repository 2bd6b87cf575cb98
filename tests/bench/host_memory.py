#!/usr/bin/python3
"""Host memory of local bakes: the submit-time estimate against the measured peak.

Runs `luxel bake SCENE --local --samples 1 --resolution R --encoding E` for
each resolution and encoding list, reads the estimate the CLI prints ("host
mem   estimated N bytes (...)", bake/host_memory.h) and the process's peak
resident set (ru_maxrss from wait4), and kills a bake whose resident set
passes --kill-gib (a watchdog: the machine's memory is shared). Prints a
Markdown table; --json writes the rows.

    /usr/bin/python3 tests/bench/host_memory.py --luxel build/client/luxel \\
        [--scene scenes/cornell_box.gltf] [--resolutions 1024,2048] \\
        [--encodings sg12 --encodings sh1,sh2,sg6,sg9,sg12,sg6-hemi,sg9-hemi,sg12-hemi] \\
        [--denoise off] [--kill-gib 14] [--out /tmp/host_memory] [--json rows.json]
"""

import argparse
import json
import os
import pathlib
import re
import signal
import subprocess
import time


def rss_bytes(pid):
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def run(cmd, kill_bytes):
    """Runs cmd; returns (exit status, stdout text, peak RSS bytes, killed)."""
    out_path = pathlib.Path("/tmp/host_memory_stdout.%d" % os.getpid())
    with open(out_path, "w") as out:
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT)
        killed = False
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid == proc.pid:
                break
            if rss_bytes(proc.pid) > kill_bytes:
                os.kill(proc.pid, signal.SIGKILL)
                killed = True
            time.sleep(0.05)
    text = out_path.read_text()
    out_path.unlink()
    return os.waitstatus_to_exitcode(status), text, usage.ru_maxrss * 1024, killed


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxel", required=True)
    p.add_argument("--scene", default="scenes/cornell_box.gltf")
    p.add_argument("--resolutions", default="1024,2048")
    p.add_argument("--encodings", action="append")
    p.add_argument("--denoise", default="off")
    p.add_argument("--kill-gib", type=float, default=14)
    p.add_argument("--extra", default="", help="more flags for luxel bake, space-separated")
    p.add_argument("--out", default="/tmp/host_memory")
    p.add_argument("--json")
    p.add_argument("--before", action="store_true",
                   help="a binary without --host-memory-budget (no estimate)")
    args = p.parse_args()
    encodings = args.encodings or ["sg12", "sh1,sh2,sg6,sg9,sg12,sg6-hemi,sg9-hemi,sg12-hemi"]
    rows = []
    print("| resolution | encodings | denoise | estimate GiB | peak RSS GiB | peak / estimate | s |")
    print("|---:|---|---|---:|---:|---:|---:|")
    for res in [int(r) for r in args.resolutions.split(",")]:
        for enc in encodings:
            out = pathlib.Path(args.out) / ("%d_%s" % (res, enc.replace(",", "+")))
            cmd = [args.luxel, "bake", args.scene, "--local", "--out", str(out), "--samples", "1",
                   "--resolution", str(res), "--encoding", enc, "--denoise", args.denoise,
                   ] + ([] if args.before else ["--host-memory-budget", "0"]) + args.extra.split()
            t0 = time.monotonic()
            code, text, peak, killed = run(cmd, int(args.kill_gib * 2**30))
            seconds = time.monotonic() - t0
            m = re.search(r"host mem\s+estimated (\d+) bytes \(([^)]*)\)", text)
            estimate = int(m.group(1)) if m else 0
            row = {"resolution": res, "encodings": enc, "denoise": args.denoise,
                   "estimate_bytes": estimate, "breakdown": m.group(2) if m else "",
                   "peak_rss_bytes": peak, "exit": code, "killed": killed, "seconds": seconds}
            rows.append(row)
            note = " (killed past %.0f GiB)" % args.kill_gib if killed else (
                "" if code == 0 else " (exit %d)" % code)
            print("| %d | %s | %s | %.2f | %.2f%s | %s | %.0f |" % (
                res, enc, args.denoise, estimate / 2**30, peak / 2**30, note,
                "%.2f" % (peak / estimate) if estimate else "-", seconds), flush=True)
            if code != 0 and not killed:
                print(text[-2000:])
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
