#!/usr/bin/python3
"""Scene import time against the node count (`luxel inspect --no-trace`).

Writes glTF files of N nodes sharing one triangle, side by side (every node a
root) and as a chain (each node the child of the one before), and times
`luxel inspect FILE --no-trace` (import, scene statistics, the OpenCL device
and BVH build; no rays) per file, for each binary given. A linear import
doubles its time per doubling of N (beyond the fixed cost of the smallest
size); a quadratic one quadruples it.

    /usr/bin/python3 tests/bench/import_nodes.py --luxel build/client/luxel [--luxel OTHER] \
        [--sizes 12500,25000,50000,100000] [--out /tmp/import_nodes]
"""

import argparse
import base64
import json
import pathlib
import struct
import subprocess
import time


def write_graph(path, n, chain):
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 0, 1)
    nodes = []
    for i in range(n):
        node = {"mesh": 0, "translation": [0.001 if chain else 0.001 * i, 0, 0]}
        if chain and i + 1 < n:
            node["children"] = [i + 1]
        nodes.append(node)
    doc = {"asset": {"version": "2.0"},
           "buffers": [{"byteLength": len(pos),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(pos).decode()}],
           "bufferViews": [{"buffer": 0, "byteLength": len(pos)}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 0, 1]}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "nodes": nodes, "scenes": [{"nodes": [0] if chain else list(range(n))}], "scene": 0}
    path.write_text(json.dumps(doc))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxel", action="append", required=True, help="a luxel binary (repeat to compare)")
    p.add_argument("--sizes", default="12500,25000,50000,100000")
    p.add_argument("--out", default="/tmp/import_nodes")
    p.add_argument("--timeout", type=float, default=600)
    args = p.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    sizes = [int(s) for s in args.sizes.split(",")]
    print("| layout | nodes | file MB | " + " | ".join("%s s" % b for b in args.luxel) + " |")
    print("|---|---:|---:|" + "---:|" * len(args.luxel))
    for layout in ("flat", "chain"):
        for n in sizes:
            f = out / ("%s_%d.gltf" % (layout, n))
            if not f.exists():
                write_graph(f, n, layout == "chain")
            row = []
            for b in args.luxel:
                t0 = time.monotonic()
                r = subprocess.run([b, "inspect", str(f), "--no-trace"], capture_output=True, text=True,
                                   timeout=args.timeout)
                dt = time.monotonic() - t0
                row.append("%.2f" % dt if r.returncode == 0 else "failed (%d)" % r.returncode)
            print("| %s | %d | %.1f | %s |" % (layout, n, f.stat().st_size / 1e6, " | ".join(row)), flush=True)


if __name__ == "__main__":
    main()
