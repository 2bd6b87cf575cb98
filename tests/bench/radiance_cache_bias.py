#!/usr/bin/python3
"""The radiance cache's bias: cached bakes against a converged traced reference at 16, 64, 256 spp.

For each scene, a converged reference (the traced estimator, --reference-spp
samples, seed + 1000, cached as error_vs_time.py caches its references), then
at each sample count `--seeds` bakes with the radiance cache and as many
without it (the control: the traced estimator is unbiased, so its reading
shows what the measurement's own noise allows). Bias of a texel class =
sum(x - ref) / sum(ref) over the class, luminance, averaged over the seeds,
with its standard error from the seeds' spread (each seed is an independent
bake, so the spread includes the cache's noise shared between texels).

Texel classes: all covered texels; "near edges", the covered texels within 2
texels of an uncovered one (chart borders: where walls meet floors and
ceilings, corners, the rims of thin walls); "interior", the rest. The edges
are where a final gather's texel averages span a crease, so the bias
concentrates there if anywhere. Raw maps (--denoise off), adaptive sampling
off (both sides the same samples per texel).

    /usr/bin/python3 tests/bench/radiance_cache_bias.py --luxel build/client/luxel \
        --scenes cornell_box,shared --shared-resolution 128
"""

import argparse
import json
import math
import pathlib
import re
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import equal_error as ee  # noqa: E402
import error_vs_time as evt  # noqa: E402


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxel", default=str(evt._REPO / "build/client/luxel"))
    p.add_argument("--out", default=str(evt._REPO / "out/radiance_cache_bias"))
    p.add_argument("--scenes", default="cornell_box,shared")
    p.add_argument("--spp", default="16,64,256")
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--configs", default="traced,cache", help="traced (the control), cache")
    ee.add_reference_args(p, resolution=128, shared_resolution=128)
    p.add_argument("--paths-per-iteration", type=int, default=65536)
    p.add_argument("--luxel-opts", default="", help="more bake options for both configs, e.g. --no-seam-stitch")
    a = p.parse_args(argv)
    a.out = pathlib.Path(a.out)
    a.reference_cache = pathlib.Path(a.reference_cache) if a.reference_cache else a.out / "references"
    a.spp_list = [int(x) for x in a.spp.split(",") if x.strip()]
    return a


def class_bias(x, ref, mask):
    """sum(x - ref) / sum(ref) over the mask, luminance."""
    lx, lr = evt.luminance(x[..., :3]), evt.luminance(ref[..., :3])
    s = float(lr[mask].sum())
    return float((lx[mask] - lr[mask]).sum()) / s if s > 0 else math.nan


def main(argv):
    args = parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    machine = evt.machine_info(args.luxel)
    m = re.search(r"(\d+\.\d+\.\d+)", machine["luxel_version"])
    version = m.group(1) if m else machine["luxel_version"]
    rows, failures = [], []
    traced = evt.traced_options(args.luxel)
    t0 = time.monotonic()
    for name, path, res in ee.scene_list(args):
        print("\n== %s (%s, %d^2)" % (name, path, res), flush=True)
        a = argparse.Namespace(**vars(args))
        a.resolution = res
        ref_dir, ok, msg = evt.reference_with(a, name, path, "box", version,
                                              ["--no-adaptive"] + traced + ee.lights(name))
        if not ok:
            failures.append("%s: reference failed: %s" % (name, msg))
            continue
        ref = evt.read_exr(ref_dir / "irradiance.exr")
        cov = ref[..., 3] > 0
        edge = ee.edge_mask(cov)
        classes = {"all": cov, "edges": edge, "interior": cov & ~edge}
        for spp in args.spp_list:
            for cfg, extra in (("traced", traced), ("cache", [])):
                if cfg not in args.configs.split(","):
                    continue
                per_seed = {k: [] for k in classes}
                for k in range(args.seeds):
                    d = args.out / name / ("%s_%d_s%d" % (cfg, spp, k))
                    opts = ["--samples", str(spp), "--seed", str(args.seed + k), "--no-adaptive",
                            "--denoise", "off", "--paths-per-iteration", str(args.paths_per_iteration)]
                    ok, msg = evt.bake(a, path, d, opts + args.luxel_opts.split() + extra + ee.lights(name))
                    if not ok:
                        failures.append("%s/%s/%d: %s" % (name, cfg, spp, msg))
                        continue
                    x = evt.read_exr(d / "irradiance.exr")
                    for c, m in classes.items():
                        per_seed[c].append(class_bias(x, ref, m))
                row = {"scene": name, "resolution": res, "spp": spp, "config": cfg}
                for c, v in per_seed.items():
                    v = np.asarray(v, dtype=float)
                    row[c] = float(v.mean()) if v.size else math.nan
                    row[c + "_se"] = float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan
                    row[c + "_texels"] = int(classes[c].sum())
                rows.append(row)
                print("  %-6s %4d spp  all %+.4f (+-%.4f)  edges %+.4f (+-%.4f)  interior %+.4f (+-%.4f)"
                      % (cfg, spp, row["all"], row["all_se"], row["edges"], row["edges_se"],
                         row["interior"], row["interior_se"]), flush=True)
    res = {"machine": machine, "seeds": args.seeds, "rows": rows, "failures": failures,
           "seconds": time.monotonic() - t0}
    (args.out / "results.json").write_text(json.dumps(res, indent=1), encoding="utf-8")
    print("\n| scene | spp | config | bias, all texels | near edges | interior |")
    print("|---|---:|---|---:|---:|---:|")
    for r in rows:
        print("| %s %d² | %d | %s | %+.2f %% ± %.2f | %+.2f %% ± %.2f | %+.2f %% ± %.2f |"
              % (r["scene"], r["resolution"], r["spp"], r["config"], 100 * r["all"], 100 * r["all_se"],
                 100 * r["edges"], 100 * r["edges_se"], 100 * r["interior"], 100 * r["interior_se"]))
    for f in failures:
        print("FAILED: " + f)
    print("\n%d s" % res["seconds"])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
