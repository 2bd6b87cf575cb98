#!/usr/bin/python3
"""Peak memory of luxeld while it imports hostile uploads (docs/operations.md,
"Import budgets").

For each case, a fresh luxeld (each binary given, with its default flags plus
any given after --) receives the upload(s); the script reports the daemon's
resident memory before (VmRSS once it answers), its peak (VmHWM, and VmRSS
sampled every 10 ms), the time the upload took and how it ended. A watchdog
kills the daemon when its VmRSS passes --rss-limit-mb (the case then reads
"killed"). Cases:

  zeros      a .gltf whose POSITION accessor has no bufferView and 3 * 2^24
             vertices (zeros, glTF 2.0 §3.6.2.3): 0.5 KB of JSON
  instances  a quad on a node with EXT_mesh_gpu_instancing, 10^6 instances
             from a TRANSLATION accessor without a bufferView
  png        four all-zero greyscale PNGs of 16384 x 4000 in one .gltf
  png4       four such files (different bytes) uploaded at once

    PYTHONPATH=client/python:BUILD/python /usr/bin/python3 tests/bench/import_limits.py \\
        --luxeld "BUILD/server/service/luxeld --import-memory-budget 1TiB" \\
        --luxeld BUILD/server/service/luxeld [--cases zeros,instances,png,png4] [-- extra luxeld flags]

(A 1 TiB budget switches the byte budget off: the import then allocates what
it did before the budget existed, bounded only by the 2^30-element limit.)
"""

import argparse
import base64
import json
import os
import pathlib
import signal
import struct
import sys
import tempfile
import threading
import time
import zlib

_REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(_REPO / "client/python"))
sys.path.insert(0, str(_REPO / "tests/python"))

from luxel_client import Client, LuxelError  # noqa: E402
from luxeld_process import Luxeld  # noqa: E402


def proc_kb(pid, key):
    try:
        for line in pathlib.Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith(key + ":"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


def quad_doc():
    pos = struct.pack("<12f", 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0)
    idx = struct.pack("<6I", 0, 1, 2, 0, 2, 3)
    data = pos + idx
    return {"asset": {"version": "2.0"},
            "buffers": [{"byteLength": len(data),
                         "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
            "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"}],
            "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "nodes": [{"mesh": 0, "name": "n"}], "scenes": [{"nodes": [0]}], "scene": 0}


def zeros_gltf():
    doc = {"asset": {"version": "2.0"},
           "accessors": [{"componentType": 5126, "count": 3 << 24, "type": "VEC3",
                          "min": [0, 0, 0], "max": [0, 0, 0]}],
           "meshes": [{"name": "bomb", "primitives": [{"attributes": {"POSITION": 0}}]}],
           "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}
    return json.dumps(doc)


def instances_gltf():
    doc = quad_doc()
    doc["accessors"].append({"componentType": 5126, "count": 1000000, "type": "VEC3",
                             "min": [0, 0, 0], "max": [0, 0, 0]})
    doc["nodes"][0]["extensions"] = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 2}}}
    doc["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    return json.dumps(doc)


def zero_png(w, h, tag):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)  # 8-bit greyscale
    raw = bytearray(h * (w + 1))
    raw[-1] = tag  # one pixel differs per file, so each upload is a new scene
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw), 9))
            + chunk(b"IEND", b""))


def png_gltf(tag):
    doc = quad_doc()
    doc["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(zero_png(16384, 4000, tag * 4 + i)).decode()}
                     for i in range(4)]
    doc["textures"] = [{"source": i} for i in range(4)]
    doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                  "metallicRoughnessTexture": {"index": 1}},
                         "emissiveTexture": {"index": 2}, "normalTexture": {"index": 3}}]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    return json.dumps(doc)


def run_case(binary, extra, files, rss_limit_kb):
    daemon = Luxeld(binary, extra_args=extra).start()
    pid = daemon.process.pid
    before = proc_kb(pid, "VmRSS")
    peak = [before]
    stop = threading.Event()
    killed = [False]

    def sample():
        while not stop.is_set():
            rss = proc_kb(pid, "VmRSS")
            peak[0] = max(peak[0], rss)
            if rss > rss_limit_kb:
                killed[0] = True
                os.kill(pid, signal.SIGKILL)
                return
            time.sleep(0.01)

    sampler = threading.Thread(target=sample)
    sampler.start()
    results = [None] * len(files)

    def upload(i, path):
        t0 = time.monotonic()
        try:
            with Client(daemon.address) as c:
                c.upload_scene(str(path))
            results[i] = ("OK", time.monotonic() - t0, "")
        except LuxelError as e:
            results[i] = (getattr(e, "code", "ERROR"), time.monotonic() - t0, str(e))
        except Exception as e:  # the daemon was killed: the channel breaks
            results[i] = ("killed" if killed[0] else type(e).__name__, time.monotonic() - t0, str(e))

    threads = [threading.Thread(target=upload, args=(i, f)) for i, f in enumerate(files)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    hwm = proc_kb(pid, "VmHWM")
    stop.set()
    sampler.join()
    daemon.stop()
    daemon.cleanup()
    return before, max(hwm, peak[0]), results


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxeld", action="append", required=True,
                   help="a luxeld binary, optionally with its own flags ('BIN --flag V'); repeat to compare")
    p.add_argument("--cases", default="zeros,instances,png,png4")
    p.add_argument("--rss-limit-mb", type=int, default=6144)
    p.add_argument("extra", nargs="*", help="flags passed to every luxeld (after --)")
    args = p.parse_args(argv)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="import_limits_"))
    makers = {"zeros": lambda: [zeros_gltf()], "instances": lambda: [instances_gltf()],
              "png": lambda: [png_gltf(1)], "png4": lambda: [png_gltf(10 + i) for i in range(4)]}
    print("| luxeld | case | file KB | RSS before MiB | peak MiB | +MiB | seconds | result |")
    print("|---|---|---:|---:|---:|---:|---:|---|")
    for case in args.cases.split(","):
        files = []
        for i, text in enumerate(makers[case]()):
            f = tmp / f"{case}{i}.gltf"
            f.write_text(text)
            files.append(f)
        for spec in args.luxeld:
            binary, *flags = spec.split()
            before, peak, results = run_case(binary, flags + args.extra, files, args.rss_limit_mb * 1024)
            codes = ", ".join(r[0] for r in results)
            secs = max(r[1] for r in results)
            print("| %s | %s | %.1f | %d | %d | %+d | %.1f | %s |" % (
                spec, case, files[0].stat().st_size / 1024, before / 1024, peak / 1024,
                (peak - before) / 1024, secs, codes), flush=True)
            for r in results:
                if r[2]:
                    print("    " + r[2][:400], flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
