#!/usr/bin/python3
"""Time to equal error: the variance-reduction features against the bake they replace.

`error_vs_time.py --equal-error` runs this (or run it directly, same options).
Each configuration switches some of the features on over the configuration
"before" (the engine's default before they existed):

  before     --direct sampled, adaptive sampling off, --denoise off, seam stitching off,
             radiance cache off
  analytic   + analytic direct light with ratio-estimator shadows
  adaptive   + adaptive sampling
  denoise    + the a-trous denoiser (RMSE of irradiance_denoised.exr)
  cache      + the radiance cache
  oidn       + Open Image Denoise's RTLightmap filter (irradiance_denoised.exr)
  all        every feature on (what the defaults are meant to be)
  all_but_X  (--leave-one-out) every feature but X
  default    no option at all: what a bake gets today
  default_raw  the defaults with --denoise off (the raw map a default bake also writes)
  default_atrous  the defaults with --denoise atrous
  default_oidn    the defaults with --denoise oidn
  previous        the defaults with --denoise off --no-seam-stitch (the release before them)
  traced          the defaults with --no-radiance-cache (every path traced to its end)
  traced_raw      the defaults with --no-radiance-cache --denoise off
  guide, guide_raw  the defaults with --guiding (denoised, raw)
  guide_traced, guide_traced_raw  the defaults with --guiding --no-radiance-cache

Settings come from `luxel settings --json`, so the flags follow the schema; a
configuration that needs a setting the binary lacks is reported as absent.

For each scene:
1. Reference: an unbiased converged bake (the "before" estimator, --reference-spp
   samples, seed + 1000), cached as error_vs_time.py caches its references.
2. For each configuration and each time budget t of the ladder, one bake with
   --time t (a denoised map exists only at the end of a bake, so no
   one-bake-per-configuration reading here). Its cost is its tracing time plus
   the post-processing it adds (denoise, stitching: their seconds in the
   manifest), so a filter that costs time pays for it.
3. RMSE and sqrt(relMSE) of the final map against the reference over the
   reference's covered texels (bias included), and the RMSE on texels near a
   geometric edge (the reference's covered texels with an uncovered or
   differently-lit neighbour are not used: near edges = texels within 2 texels
   of a chart border).
4. Time to equal RMSE: the cost at which the configuration reaches the RMSE
   "before" reaches at the largest budget (log-log interpolation along its
   ladder). Below the smallest budget it is extrapolated with slope -1/2
   (plain Monte Carlo; a filtered map falls more slowly, so the true time is
   shorter and the speed-up a lower bound), above the largest with the slope
   of its last two points (never: the error stops falling). speed-up = the
   largest budget / that time.

    /usr/bin/python3 tests/bench/error_vs_time.py --equal-error --out out/equal_error
"""

import argparse
import json
import math
import pathlib
import re
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import error_vs_time as evt  # noqa: E402

_REPO = evt._REPO

FEATURES = {  # feature -> (setting name, value when on, value when off)
    "analytic": ("direct", "analytic", "sampled"),
    "adaptive": ("adaptive", True, False),
    "denoise": ("denoise", "atrous", "off"),
    "stitch": ("seam_stitch", True, False),
    "cache": ("radiance_cache", True, False),
}
SHARED = ["cornell_box.glb", "breakfast_room.glb", "sponza.glb", "gas_station.glb"]


# Configurations that change one setting of another configuration:
# name -> (base features, {setting name: value}). A base of None is the
# defaults.
VARIANTS = {"oidn": ({"denoise"}, {"denoise": "oidn"}),
            "default_raw": (None, {"denoise": "off"}),
            "default_oidn": (None, {"denoise": "oidn"}),
            "default_atrous": (None, {"denoise": "atrous"}),
            # The defaults of the release before denoise = auto and seam stitching
            # (the analytic estimator for punctual lights is today's non-negative one).
            "previous": (None, {"denoise": "off", "seam_stitch": False}),
            # The defaults without the radiance cache (kernels/bake/radiance_cache.h),
            # denoised and raw: the default before the cache.
            "traced": (None, {"radiance_cache": False}),
            "traced_raw": (None, {"denoise": "off", "radiance_cache": False}),
            # First-bounce guiding (kernels/bake/guiding.h), with the cache and without.
            "guide": (None, {"guiding": True}),
            "guide_raw": (None, {"denoise": "off", "guiding": True}),
            "guide_traced": (None, {"radiance_cache": False, "guiding": True}),
            "guide_traced_raw": (None, {"denoise": "off", "radiance_cache": False, "guiding": True})}


def configs(leave_one_out):
    # "default": no option at all, what a bake gets today (its features are
    # whatever the defaults are: None).
    out = [("before", set()), ("default", None), ("analytic", {"analytic"}), ("adaptive", {"adaptive"}),
           ("denoise", {"denoise"}), ("stitch", {"stitch"}), ("all", set(FEATURES))]
    out += [(name, base) for name, (base, _) in VARIANTS.items()]
    if leave_one_out:
        out += [("all_but_" + f, set(FEATURES) - {f}) for f in FEATURES if f != "stitch"]
    return out


def add_reference_args(p, resolution, shared_resolution):
    """The options of a bench that bakes the scenes against cached converged references
    (error_vs_time.reference_with): reference samples and cache, lightmap sides, bounces,
    the first seed and the device."""
    p.add_argument("--reference-spp", type=int, default=4096)
    p.add_argument("--reference-cache", default=None)
    p.add_argument("--resolution", type=int, default=resolution)
    p.add_argument("--shared-resolution", type=int, default=shared_resolution,
                   help="lightmap side for ../shared/scenes")
    p.add_argument("--bounces", type=int, default=4)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--device", default=None)


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--equal-error", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--luxel", default=str(_REPO / "build/client/luxel"))
    p.add_argument("--out", default=str(_REPO / "out/equal_error"))
    p.add_argument("--scenes", default="cornell_box,foliage_instanced,procedural_city,shared",
                   help="bundled names, paths, 'shared' (../shared/scenes) and 'peers' (tests/bench/peers scenes "
                        "made by make_scenes.py into OUT/peer_scenes)")
    p.add_argument("--budgets", default="0.5,1,2,4", help="time budgets in seconds")
    add_reference_args(p, resolution=128, shared_resolution=256)
    p.add_argument("--paths-per-iteration", type=int, default=65536)
    p.add_argument("--leave-one-out", action="store_true", help="also all_but_X configurations")
    p.add_argument("--configs", default=None,
                   help="comma-separated configurations to run (default: all; 'before' is always run)")
    p.add_argument("--quick", action="store_true", help="smoke run: Cornell box 32^2, budgets 0.2,0.4")
    a = p.parse_args(argv)
    if a.quick:
        a.scenes, a.budgets, a.resolution, a.reference_spp = "cornell_box", "0.2,0.4", 32, 1024
        a.paths_per_iteration = 8192
    a.budget_list = sorted(float(b) for b in a.budgets.split(","))
    a.out = pathlib.Path(a.out).resolve()
    a.reference_cache = pathlib.Path(a.reference_cache or a.out / "references").resolve()
    return a


def schema(luxel):
    r = subprocess.run([luxel, "settings", "--json"], capture_output=True, text=True, check=True)
    return {s["name"]: s for s in json.loads(r.stdout)["settings"]}


def options_for(features_on, sch, overrides=None):
    """CLI options that set every feature on or off; None when a needed setting is missing.
    features_on None: no options (the defaults). `overrides`: {setting: value} replacing what a
    feature sets (or added to the defaults)."""
    overrides = overrides or {}
    for name, want in overrides.items():
        if name not in sch or (sch[name].get("choices") and want not in sch[name]["choices"]):
            return None
    if features_on is None:
        opts = []
        for name, want in overrides.items():
            if sch[name]["type"] == "bool":
                if bool(sch[name]["default"]) != bool(want):
                    opts.append(sch[name]["flag"])  # the flag turns the default around
            elif str(sch[name]["default"]) != str(want):
                opts += [sch[name]["flag"], str(want)]
        return opts
    opts = []
    for f, (name, on, off) in FEATURES.items():
        want = overrides.get(name, on) if f in features_on else off
        s = sch.get(name)
        if s is None:
            if f in features_on:
                return None
            continue  # the binary predates the feature: off is all it does
        if s["type"] == "bool":
            if bool(s["default"]) != want:
                opts.append(s["flag"])
        elif str(s["default"]) != want:
            opts += [s["flag"], want]
    return opts


def scene_list(args):
    out = []
    for item in [s.strip() for s in args.scenes.split(",") if s.strip()]:
        if item == "shared":
            d = _REPO.parent / "shared" / "scenes"
            out += [("shared_" + f.split(".")[0], d / f, args.shared_resolution) for f in SHARED if (d / f).is_file()]
        elif item == "peers":
            d = args.out / "peer_scenes"
            d.mkdir(parents=True, exist_ok=True)
            subprocess.run([sys.executable, str(_REPO / "tests/bench/peers/make_scenes.py"), str(d)], check=False)
            out += [("peer_" + f.stem, f, args.resolution) for f in sorted(d.glob("*courtyard.gltf"))]
        else:
            path = pathlib.Path(evt.BUNDLED.get(item, item))
            path = path if path.is_absolute() else _REPO / path
            name = item if item in evt.BUNDLED else ("shared_" if "shared" in path.parts else "") + path.stem
            res = args.shared_resolution if name.startswith("shared_") else args.resolution
            out.append((name, path, res))
    return out


def lights(name):
    """The lighting of a scene without lights of its own (as error_vs_time.py and run_peer_bench.sh)."""
    if "cornell" in name.lower() or name.startswith("peer_lights"):
        return []
    if name.startswith("peer_sky"):
        return ["--sky", "0.5,0.8,1.0"]  # run_peer_bench.sh's SKY
    return list(evt.SKY_SUN)


def post_seconds(manifest):
    """Seconds the bake spent after tracing on what a configuration adds (denoise, stitching)."""
    s = 0.0
    for key in ("denoise", "seam_stitch"):
        v = manifest.get(key)
        if not isinstance(v, dict):
            continue
        if isinstance(v.get("seconds"), (int, float)):  # the whole step (its parts are inside it)
            s += float(v["seconds"])
        else:  # "find_seconds", "stitch_seconds", ...
            s += sum(float(x) for k, x in v.items() if k.endswith("seconds") and isinstance(x, (int, float)))
    return s


def edge_mask(cov, radius=2):
    """Covered texels within `radius` texels of an uncovered one (chart borders, creases between charts)."""
    unc = ~cov
    near = np.zeros_like(cov)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            near |= np.roll(np.roll(unc, dy, axis=0), dx, axis=1)
    return cov & near


def errors(map_path, ref):
    x = evt.read_exr(map_path)
    cov = ref[..., 3] > 0
    d = x[..., :3] - ref[..., :3]
    rel = d ** 2 / (ref[..., :3] ** 2 + 1e-2)
    edge = edge_mask(cov)
    return {"rmse": float(np.sqrt(np.mean(d[cov] ** 2))),
            "sqrt_rel_mse": float(np.sqrt(np.mean(rel[cov]))),
            "rmse_edges": float(np.sqrt(np.mean(d[edge] ** 2))) if edge.any() else math.nan,
            "edge_texels": int(edge.sum()), "texels": int(cov.sum())}


def time_to(costs, rmses, target):
    """(cost at which the ladder reaches target, how it was read)."""
    c, e = np.log(np.asarray(costs)), np.log(np.asarray(rmses))
    lt = math.log(target)
    if e[0] <= lt:
        return float(np.exp(c[0] - 2.0 * (lt - e[0]))), "extrapolated, slope -1/2"
    for i in range(1, len(c)):
        if e[i] <= lt:
            f = (lt - e[i - 1]) / (e[i] - e[i - 1])
            return float(np.exp(c[i - 1] + f * (c[i] - c[i - 1]))), "interpolated"
    if len(c) >= 2 and e[-1] < e[-2]:
        slope = (e[-1] - e[-2]) / (c[-1] - c[-2])
        return float(np.exp(c[-1] + (lt - e[-1]) / slope)), "extrapolated, slope %.2f" % slope
    return math.inf, "never (error stops falling)"


def main(argv):
    args = parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    sch = schema(args.luxel)
    machine = evt.machine_info(args.luxel)
    m = re.search(r"(\d+\.\d+\.\d+)", machine["luxel_version"])
    version = m.group(1) if m else machine["luxel_version"]
    ref_opts = options_for(set(), sch)
    cfgs = configs(args.leave_one_out)
    if args.configs:
        wanted = {"before"} | {c.strip() for c in args.configs.split(",") if c.strip()}
        unknown = wanted - {c for c, _ in cfgs}
        if unknown:
            sys.exit("unknown configuration(s): %s" % ", ".join(sorted(unknown)))
        cfgs = [(c, on) for c, on in cfgs if c in wanted]
    results, failures = {"machine": machine, "budgets": args.budget_list, "scenes": {}}, []
    t_start = time.monotonic()
    for name, path, res in scene_list(args):
        print("\n== %s (%s, %d^2)" % (name, path, res), flush=True)
        if not path.is_file():
            failures.append("%s: %s not found" % (name, path))
            continue
        a = argparse.Namespace(**vars(args))
        a.resolution = res
        ref_dir, ok, msg = evt.reference_with(a, name, path, "box", version, ref_opts + lights(name))
        if not ok:
            failures.append("%s: reference failed: %s" % (name, msg))
            continue
        ref = evt.read_exr(ref_dir / "irradiance.exr")
        sres = {"resolution": res, "reference": str(ref_dir), "configs": {}}
        results["scenes"][name] = sres
        for cname, on in cfgs:
            opts = options_for(on, sch, VARIANTS.get(cname, (None, {}))[1])
            if opts is None:
                sres["configs"][cname] = {"absent": True}
                print("  %-16s absent (the binary lacks a setting)" % cname, flush=True)
                continue
            base = ["--seed", str(args.seed), "--paths-per-iteration", str(args.paths_per_iteration),
                    "--samples", "0"] + opts + lights(name)
            evt.bake(a, path, args.out / name / "warmup", base + ["--time", "0.3"])
            ladder = []
            for b in args.budget_list:
                bdir = args.out / name / ("%s_t%g" % (cname, b))
                ok, msg = evt.bake(a, path, bdir, base + ["--time", "%g" % b])
                if not ok:
                    failures.append("%s/%s at %g s: %s" % (name, cname, b, msg))
                    continue
                man = json.loads((bdir / "manifest.json").read_text(encoding="utf-8"))
                # The map a user gets: the denoised one whenever the bake wrote it.
                denoised = any(f.get("role") == "irradiance_denoised" for f in man.get("files", []))
                if on is not None and "denoise" in on and not denoised:
                    failures.append("%s/%s: no denoised map (%s)" % (name, cname, man.get("denoise")))
                    continue
                fmap = bdir / ("irradiance_denoised.exr" if denoised else "irradiance.exr")
                if not fmap.is_file():
                    failures.append("%s/%s: %s missing" % (name, cname, fmap.name))
                    continue
                e = errors(fmap, ref)
                e.update({"budget_s": b, "tracing_s": man["stats"]["seconds"], "post_s": post_seconds(man),
                          "paths": man["stats"]["paths"]})
                ladder.append(e)
            # Cost of each point: its paths at the configuration's mean
            # throughput over the whole ladder, plus its post-processing. A
            # single run's own tracing time carries the machine's run-to-run
            # throughput noise (+-10-20 % in 4 s on the shared 2-core VM:
            # configurations with the same estimator came out 0.64x-1.41x);
            # the ladder's mean carries much less, and the RMSE at a given
            # path count is deterministic.
            traced = sum(x["tracing_s"] for x in ladder)
            rate = sum(x["paths"] for x in ladder) / traced if traced > 0 else math.nan
            for x in ladder:
                x["paths_per_s"] = rate
                x["cost_s"] = x["paths"] / rate + x["post_s"] if rate > 0 else x["tracing_s"] + x["post_s"]
            sres["configs"][cname] = {"features": sorted(on) if on is not None else "defaults",
                                      "options": opts, "ladder": ladder}
            last = ladder[-1] if ladder else {}
            print("  %-16s %s" % (cname, "  ".join("%gs: %.4g" % (x["budget_s"], x["rmse"]) for x in ladder)),
                  flush=True)
            if last:
                print("  %-16s post %.3f s, edges RMSE %.4g" % ("", last["post_s"], last["rmse_edges"]), flush=True)
        before = sres["configs"].get("before", {}).get("ladder")
        if not before:
            continue
        target = before[-1]["rmse"]
        t_ref = before[-1]["cost_s"]
        for cname, c in sres["configs"].items():
            if c.get("absent") or not c["ladder"]:
                continue
            if cname == "before":
                t, how = t_ref, "the target"
            else:
                t, how = time_to([x["cost_s"] for x in c["ladder"]], [x["rmse"] for x in c["ladder"]], target)
            c["time_to_target_s"], c["how"], c["speedup"] = t, how, t_ref / t if t > 0 else math.inf
            eq = c["ladder"][-1]
            c["rmse_ratio_at_largest"] = eq["rmse"] / before[-1]["rmse"]
            c["edge_ratio_at_largest"] = eq["rmse_edges"] / before[-1]["rmse_edges"]
    results["failures"] = failures
    results["wall_s"] = time.monotonic() - t_start
    (args.out / "equal_error.json").write_text(json.dumps(results, indent=1, default=str), encoding="utf-8")
    md = markdown(args, results)
    (args.out / "equal_error.md").write_text(md, encoding="utf-8")
    print("\n" + md)
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures), file=sys.stderr)
    return 1 if failures else 0


def markdown(args, res):
    m = res["machine"]
    out = ["# Time to equal error (`tests/bench/error_vs_time.py --equal-error`)", "",
           "- machine: %s, %s hardware threads; git %s; %s" % (m["cpu_model"], m["hardware_threads"],
                                                              m["git_revision"], m["luxel_version"]),
           "- budgets %s s, %d bounces, seed %d, reference %d spp (before's estimator, seed %d), run %.0f s" % (
               ", ".join("%g" % b for b in args.budget_list), args.bounces, args.seed, args.reference_spp,
               args.seed + 1000, res["wall_s"]), "",
           "speed-up = cost of `before` at the largest budget / cost at which the configuration reaches the same "
           "RMSE (cost = paths at the configuration's mean paths/s over its ladder + the post-processing it "
           "adds). RMSE ratio: at the largest budget, "
           "configuration / before (< 1 better), on all covered texels and on texels within 2 texels of a "
           "chart border.", "",
           "| scene | config | speed-up | read | RMSE ratio | edge RMSE ratio | post s | Mpaths/s |",
           "|---|---|---:|---|---:|---:|---:|---:|"]
    for name, s in res["scenes"].items():
        for cname, c in s["configs"].items():
            if c.get("absent"):
                out.append("| %s | %s | absent | | | | | |" % (name, cname))
                continue
            if "speedup" not in c:
                continue
            out.append("| %s %d² | %s | %s | %s | %s | %s | %.3f | %.2f |" % (
                name, s["resolution"], cname, evt.fmt(c["speedup"], ".2f"), c["how"],
                evt.fmt(c["rmse_ratio_at_largest"], ".3f"), evt.fmt(c["edge_ratio_at_largest"], ".3f"),
                c["ladder"][-1]["post_s"], c["ladder"][-1]["paths_per_s"] / 1e6))
    if res["failures"]:
        out += ["", "## Failures", ""] + ["- " + f for f in res["failures"]]
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
