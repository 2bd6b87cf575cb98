#!/usr/bin/env python3
"""Bake throughput (paths/s) of two builds side by side in one run.

    throughput_ab.py --base BASE/bench_bake --new NEW/bench_bake [--rounds 3]
                     [--spp 16] [--resolution 256] SCENE...

Each round bakes every scene with the base build and then the new one
(bench_bake --default-only: the default settings, a sky and a sun, each bake
measured after a warm-up bake of its own), so both builds see the same
machine state, and slow drifts of the machine fall on both. Prints each
build's median Mpaths/s per scene, the ratio new / base, and the spread of
the per-round ratios. A kernel-only change can also be measured with one
binary and two kernel folders (--base-kernels / --new-kernels, through
LUXEL_KERNEL_DIR).
"""
import argparse
import os
import re
import statistics
import subprocess
import sys

ROW = re.compile(r"bounces 4 \(default\)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+(\d+)\s+(.*)")


def bake(binary, kernels, scene, spp, resolution):
    env = dict(os.environ)
    if kernels:
        env["LUXEL_KERNEL_DIR"] = kernels
    out = subprocess.run(
        [binary, "--default-only", "--kernels", "3", "--spp", str(spp),
         "--resolution", str(resolution), scene],
        env=env, capture_output=True, text=True, check=True).stdout
    m = ROW.search(out)
    if not m:
        sys.exit(f"throughput_ab: no default row from {binary} on {scene}:\n{out}")
    return float(m.group(2)), m.group(5).strip()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", required=True, help="bench_bake of the base build")
    ap.add_argument("--new", help="bench_bake of the new build (default: --base)")
    ap.add_argument("--base-kernels", help="LUXEL_KERNEL_DIR for the base runs")
    ap.add_argument("--new-kernels", help="LUXEL_KERNEL_DIR for the new runs")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--resolution", type=int, default=256)
    ap.add_argument("scenes", nargs="+")
    a = ap.parse_args()
    new = a.new or a.base
    rates = {s: ([], []) for s in a.scenes}
    split = {}
    for r in range(a.rounds):
        for s in a.scenes:
            b, _ = bake(a.base, a.base_kernels, s, a.spp, a.resolution)
            n, top = bake(new, a.new_kernels, s, a.spp, a.resolution)
            rates[s][0].append(b)
            rates[s][1].append(n)
            split[s] = top
            print(f"round {r + 1} {os.path.basename(s)}: base {b:.3f} new {n:.3f} Mpaths/s",
                  flush=True)
    print(f"\n{a.resolution}^2, {a.spp} spp per bake, {a.rounds} rounds, medians:")
    print(f"{'scene':28} {'base':>8} {'new':>8} {'new/base':>9} {'rounds':>14}  new split")
    for s in a.scenes:
        b, n = rates[s]
        ratios = [y / x for x, y in zip(b, n)]
        print(f"{os.path.basename(s):28} {statistics.median(b):8.3f} {statistics.median(n):8.3f} "
              f"{statistics.median(n) / statistics.median(b):8.2f}x "
              f"{min(ratios):6.2f}-{max(ratios):.2f}x  {split[s]}")


if __name__ == "__main__":
    main()
