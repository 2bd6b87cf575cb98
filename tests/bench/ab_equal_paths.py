#!/usr/bin/python3
"""Two builds or kernel folders side by side at equal paths: error against a converged reference.

For a change that moves samples or filters the map without changing what a
path costs (adaptive weights, the denoiser's layout), equal paths is the fair
comparison: each variant bakes the same scenes with the same seeds and
sample counts, and the paired ratio per seed removes most of the seeds'
spread. A variant is NAME=LUXEL[:KERNEL_DIR] (KERNEL_DIR is passed as
LUXEL_KERNEL_DIR, so one binary with two kernel folders compares kernel
changes alone).

Per scene a converged reference (the traced estimator, --reference-spp, seed
+ 1000, cached as error_vs_time.py caches its references). Errors are the
relMSE, mean over RGB of (x - ref)^2 / (ref^2 + 1e-2), over three texel sets:
  interior   coverage 1 with 8 covered neighbours (the texels the peer
             bench compares, tests/bench/peers/compare.py);
  weighted   every covered texel weighted by its coverage (the share of the
             surface it stands for);
  all        every covered texel alike.
With the denoiser on (--denoise default), also the denoise step's seconds
and the texels given to the filter, medians over the seeds.

    /usr/bin/python3 tests/bench/ab_equal_paths.py \
        --variant off=build/client/luxel:/tmp/kernels_off --variant on=build/client/luxel \
        --scenes cornell_box,peers --resolution 64 --spp 64,256 --denoise off
"""

import argparse
import json
import math
import os
import pathlib
import re
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import equal_error as ee  # noqa: E402
import error_vs_time as evt  # noqa: E402


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--variant", action="append", required=True,
                   help="NAME=LUXEL[:KERNEL_DIR], twice: the first is the base of the ratios")
    p.add_argument("--out", default=str(evt._REPO / "out/ab_equal_paths"))
    p.add_argument("--scenes", default="cornell_box,peers")
    p.add_argument("--spp", default="64,256")
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--denoise", default="off", help="off, or default (the bake's own choice)")
    ee.add_reference_args(p, resolution=64, shared_resolution=128)
    a = p.parse_args(argv)
    if len(a.variant) != 2:
        p.error("give --variant twice")
    a.variants = []
    for v in a.variant:
        name, _, rest = v.partition("=")
        luxel, _, kernels = rest.partition(":")
        a.variants.append((name, luxel, kernels or None))
    a.luxel = a.variants[0][1]  # the references' binary
    a.out = pathlib.Path(a.out)
    a.reference_cache = pathlib.Path(a.reference_cache) if a.reference_cache else a.out / "references"
    a.spp_list = [int(x) for x in a.spp.split(",") if x.strip()]
    return a


def interior_mask(alpha):
    """Coverage 1 with all 8 neighbours covered 1 (compare.py's interior texels)."""
    full = alpha >= 1.0
    pad = np.pad(full, 1)
    out = full.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            out &= pad[1 + dy:1 + dy + full.shape[0], 1 + dx:1 + dx + full.shape[1]]
    return out


def bake(args, variant, scene, res, out_dir, options):
    name, luxel, kernels = variant
    out_dir.mkdir(parents=True, exist_ok=True)
    cmd = [luxel, "bake", str(scene), "--local", "--out", str(out_dir), "--quiet", "--resolution", str(res),
           "--bounces", str(args.bounces)] + options + (["--device", args.device] if args.device else [])
    env = dict(os.environ)
    if kernels:
        env["LUXEL_KERNEL_DIR"] = kernels
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise RuntimeError("%s: exit %d: %s" % (name, r.returncode, (r.stderr or r.stdout).strip()[-400:]))
    return json.loads((out_dir / "manifest.json").read_text(encoding="utf-8"))


def rel_mse(x, ref, mask, weights=None):
    d = x[..., :3][mask] - ref[..., :3][mask]
    e = np.mean(d ** 2 / (ref[..., :3][mask] ** 2 + 1e-2), axis=1)
    return float(np.average(e, weights=weights))


def main(argv):
    args = parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    machine = evt.machine_info(args.luxel)
    m = re.search(r"(\d+\.\d+\.\d+)", machine["luxel_version"])
    version = m.group(1) if m else machine["luxel_version"]
    traced = evt.traced_options(args.luxel)
    map_name = "irradiance.exr" if args.denoise == "off" else "irradiance_denoised.exr"
    denoise = ["--denoise", "off"] if args.denoise == "off" else []
    rows, t0 = [], time.monotonic()
    for name, path, res in ee.scene_list(args):
        print("\n== %s (%s, %d^2)" % (name, path, res), flush=True)
        a = argparse.Namespace(**vars(args))
        a.resolution = res
        ref_dir, ok, msg = evt.reference_with(a, name, path, "box", version,
                                              ["--no-adaptive"] + traced + ee.lights(name))
        if not ok:
            raise RuntimeError("%s: reference failed: %s" % (name, msg))
        ref = evt.read_exr(ref_dir / "irradiance.exr")
        alpha = ref[..., 3]
        cov = alpha > 0
        inner = interior_mask(alpha)
        for spp in args.spp_list:
            row = {"scene": name, "resolution": res, "spp": spp}
            for variant in args.variants:
                vals = {"interior": [], "weighted": [], "all": [], "denoise_s": [], "filtered_texels": []}
                for k in range(args.seeds):
                    d = args.out / name / ("%s_%d_s%d" % (variant[0], spp, k))
                    man = bake(args, variant, path, res, d, ["--samples", str(spp), "--seed", str(args.seed + k)]
                               + denoise + ee.lights(name))
                    x = evt.read_exr(d / map_name)
                    vals["interior"].append(rel_mse(x, ref, inner))
                    vals["weighted"].append(rel_mse(x, ref, cov, alpha[cov]))
                    vals["all"].append(rel_mse(x, ref, cov))
                    dn = man.get("denoise") or {}
                    vals["denoise_s"].append(float(dn.get("seconds", math.nan)))
                    vals["filtered_texels"].append(float(dn.get("filtered_texels", math.nan)))
                row[variant[0]] = vals
            base, new = (v[0] for v in args.variants)
            ratio = np.asarray(row[new]["interior"]) / np.asarray(row[base]["interior"])
            row["interior_ratio"] = float(ratio.mean())
            row["interior_ratio_per_seed"] = ratio.tolist()
            rows.append(row)
            print("  %4d spp  interior %s %.5f %s %.5f (ratio %.3f, per seed %s)  weighted %.5f -> %.5f  "
                  "all %.5f -> %.5f  denoise ms %.1f -> %.1f  filtered texels %.0f -> %.0f"
                  % (spp, base, np.mean(row[base]["interior"]), new, np.mean(row[new]["interior"]),
                     ratio.mean(), " ".join("%.3f" % r for r in ratio),
                     np.mean(row[base]["weighted"]), np.mean(row[new]["weighted"]),
                     np.mean(row[base]["all"]), np.mean(row[new]["all"]),
                     1e3 * np.median(row[base]["denoise_s"]), 1e3 * np.median(row[new]["denoise_s"]),
                     np.median(row[base]["filtered_texels"]), np.median(row[new]["filtered_texels"])),
                  flush=True)
    res = {"machine": machine, "variants": args.variants, "seeds": args.seeds, "denoise": args.denoise,
           "rows": rows, "seconds": time.monotonic() - t0}
    (args.out / "results.json").write_text(json.dumps(res, indent=1), encoding="utf-8")
    print("\n%d s" % res["seconds"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
