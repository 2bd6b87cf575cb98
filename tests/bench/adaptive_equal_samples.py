#!/usr/bin/python3
"""Adaptive sampling against uniform sampling at equal samples.

For each scene: a converged reference (uniform, --reference-spp, seed 1001 so
its noise is independent of the measured bakes), then the same bake with
adaptive sampling off and on (seed 1, equal total paths: --samples is the
mean paths per covered texel), each with --reference. Reported per bake,
from the engine's own final report (error_series.csv) and kernel table:

  rmse, rel_mse    true error against the reference (the reference's own
                   noise, ~ spp / reference_spp of the bake's relMSE, adds
                   alike to both)
  estimate         the engine's reference-free error estimate (mean relative
                   standard error over covered texels)
  F                estimate / sqrt(rel_mse): the series factor of
                   tests/bench/error_vs_time.py; it must stay of the same size
                   with adaptive sampling on, or the estimate no longer tracks
                   the true error
  alloc_ms         total time of the allocation kernels (alloc_*, plus the
                   accum_stats launches that feed them) against all kernels

    /usr/bin/python3 tests/bench/adaptive_equal_samples.py --luxel build/client/luxel \\
        --out /tmp/adaptive scenes/cornell_box.gltf:64
"""
import argparse
import csv
import json
import pathlib
import re
import subprocess
import sys


# As tests/bench/error_vs_time.py: scenes without lights of their own get a
# constant sky and sun; Cornell boxes are lit by their emissive quad only.
SKY_SUN = ["--sky", "0.4,0.5,0.7", "--sun", "0.3,-1,0.2", "--sun-illuminance", "5"]


def bake(luxel, scene, out, res, spp, seed, ppi, extra):
    if "cornell" not in scene.lower():
        extra = extra + SKY_SUN
    cmd = [luxel, "bake", scene, "--local", "--out", str(out), "--resolution", str(res),
           "--samples", str(spp), "--seed", str(seed), "--paths-per-iteration", str(ppi),
           "--progress-interval", "1000"] + extra
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"bake failed: {' '.join(cmd)}\n{p.stdout}\n{p.stderr}")
    (out / "stdout.txt").write_text(p.stdout)
    return p.stdout


def kernel_ms(stdout):
    table = {}
    for line in stdout.splitlines():
        m = re.match(r"^(\w+)\s+(\d+)\s+([\d.]+)\s+[\d.]+\s+[\d.]+\s+[\d.]+%$", line)
        if m:
            table[m.group(1)] = (int(m.group(2)), float(m.group(3)))
        m = re.match(r"^total\s+([\d.]+)$", line)
        if m:
            table["total"] = (0, float(m.group(1)))
    return table


def final_row(out):
    with open(out / "error_series.csv") as f:
        rows = list(csv.DictReader(f))
    return rows[-1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenes", nargs="+", help="SCENE:RESOLUTION")
    ap.add_argument("--luxel", default="build/client/luxel")
    ap.add_argument("--out", required=True)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--reference-spp", type=int, default=2048)
    ap.add_argument("--paths-per-iteration", type=int, default=16384)
    args = ap.parse_args()
    root = pathlib.Path(args.out)
    results = []
    for item in args.scenes:
        scene, res = item.rsplit(":", 1)
        name = pathlib.Path(scene).name.replace(".", "_")  # cornell_box_gltf vs _glb
        ref = root / name / "reference"
        if not (ref / "irradiance.exr").exists():
            ref.mkdir(parents=True, exist_ok=True)
            bake(args.luxel, scene, ref, res, args.reference_spp, 1001,
                 max(args.paths_per_iteration, 1 << 18), ["--no-adaptive"])
        for label, extra in (("uniform", ["--no-adaptive"]), ("adaptive", [])):
            out = root / name / label
            out.mkdir(parents=True, exist_ok=True)
            stdout = bake(args.luxel, scene, out, res, args.spp, 1, args.paths_per_iteration,
                          extra + ["--reference", str(ref / "irradiance.exr")])
            row = final_row(out)
            k = kernel_ms(stdout)
            alloc = sum(v[1] for n, v in k.items() if n.startswith("alloc_"))
            rel_mse = float(row["rel_mse"])
            r = {"scene": name, "resolution": int(res), "mode": label,
                 "paths": int(row["paths"]), "mean_spp": float(row["mean_spp"]),
                 "min_spp": int(row["min_spp"]), "rmse": float(row["rmse"]),
                 "rel_mse": rel_mse, "estimate": float(row["rel_error"]),
                 "F": float(row["rel_error"]) / rel_mse ** 0.5 if rel_mse > 0 else float("nan"),
                 "alloc_ms": alloc, "accum_stats_ms": k.get("accum_stats", (0, 0))[1],
                 "kernels_ms": k.get("total", (0, 0))[1],
                 "alloc_launches": sum(v[0] for n, v in k.items() if n.startswith("alloc_"))}
            results.append(r)
            print(json.dumps(r), flush=True)
    (root / "summary.json").write_text(json.dumps(results, indent=1))
    print("\n| scene | res | mode | paths | min spp | RMSE | relMSE | estimate | F | "
          "RMSE adaptive/uniform | alloc ms / kernels ms |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    base = {}
    for r in results:
        key = r["scene"]
        if r["mode"] == "uniform":
            base[key] = r
        ratio = r["rmse"] / base[key]["rmse"] if base.get(key, {}).get("rmse") else float("nan")
        print(f"| {r['scene']} | {r['resolution']} | {r['mode']} | {r['paths']} | {r['min_spp']} | "
              f"{r['rmse']:.4g} | {r['rel_mse']:.4g} | {r['estimate']:.4g} | {r['F']:.3f} | "
              f"{ratio:.3f} | {r['alloc_ms'] + r['accum_stats_ms']:.1f} / {r['kernels_ms']:.0f} |")


if __name__ == "__main__":
    main()
