#!/usr/bin/python3
"""Error against run time: bundled scenes, fixed seed, a ladder of time budgets.

For each scene, in one run:

1. Reference: a high-sample bake (--reference-spp, seed --seed + 1000 so its
   noise is independent of the measured bakes) baked once and cached under
   --reference-cache (default OUT/references/KEY/), KEY = sha256 of the scene
   file's bytes (and the buffers/images a .gltf references), the reference's
   settings and the luxel version number. A rerun with the same key reuses it.
   The Gaussian-filter ablation gets its own Gaussian reference (a filtered
   bake converges to a blurred lightmap, not the box one).
2. Measured bakes, each with `--reference`: the default configuration and the
   ablations (compaction off, ray-direction sorting on, random sequence,
   Gaussian filter; tile-based indexing is not present in the engine). Each
   is ONE bake with --time = the largest budget, small batches and
   --progress-interval so error_series.csv has a point every ~0.1 s; the
   ladder of budgets is read off that series (log-log interpolation at each
   budget). With a fixed seed the progressive bake's state after t seconds is
   the state a bake with --time t stops in (the budget only decides when to
   stop, checked per iteration), so one long bake replaces one bake per
   budget at the cost of the largest budget instead of their sum. Every
   configuration first runs a short unmeasured warm-up bake so no measured
   bake pays for OpenCL program builds or PoCL's per-launch-size JIT. The
   default configuration is also baked with --time = each smaller budget, for
   the per-texel factors below and to check the one-bake reading (its RMSE
   against the long bake's series at the same tracing time).
3. Estimate against true error. Two factors, both "estimate / true" (> 1:
   the estimate is conservative):
   - series factor F(t) = rel_error / sqrt(rel_mse) at each budget: the two
     numbers a user sees side by side (the engine's estimate, mean over
     covered texels of the relative standard error of the luminance mean,
     against the RMS over texels and RGB of the regularised relative error
     with respect to the reference). They aggregate differently (mean vs RMS,
     luminance vs RGB, +1e-2 in relMSE), so F mixes calibration with the
     spread of the error over texels. F_corr uses sqrt(rel_mse - floor),
     floor = the reference's own noise in relMSE units (its rel_error.exr
     divided by the k below: an upper bound);
   - from the EXRs (needs python3-openimageio), for the default configuration
     at every budget (a bake stopped there, same seed) and for every
     configuration at the largest budget: the matched factor F_matched =
     mean r / (sqrt(pi/2) mean |e|), e = (Y - Y_ref) / Y_ref per covered
     texel (Y luminance, r the texel's estimated relative standard error from
     rel_error.exr): the estimate's own aggregation applied to the true
     deviation (E|e| = sqrt(2/pi) sigma for normal e); and the per-texel
     factor k = 1 / RMS(z), z = e / sqrt(r^2 + r_ref^2) (1 when every
     texel's estimate is exact; r_ref the reference's own estimate, so k
     accounts for the reference's noise), k_raw without r_ref, k_med =
     0.6745 / median |z| (robust to outliers).
4. Ablations: error at equal time, config / default, at the largest budget
   (log-log interpolation of each series), for RMSE, sqrt(relMSE) and the
   estimate; also the ratio of paths traced by then and the fitted slope of
   log RMSE against log time over the ladder.
5. Everything lands in --out: machine.json, per scene series.csv (every
   configuration, long form), budgets.csv, error_vs_time.png, the bake folders
   with their logs, ablations.csv, summary.md and summary.json. CSVs start
   with '#' comment lines naming the machine, git revision and settings.

    /usr/bin/python3 tests/bench/error_vs_time.py --luxel build/client/luxel --out out/bench

With --equal-error it runs tests/bench/equal_error.py instead: the time each
variance-reduction feature (analytic direct light, adaptive sampling, the
denoiser, seam stitching) needs to reach the error of the bake without them.
(options: equal_error.py --help).

Exit status: 0 when every bake succeeded, every series is non-empty and
finite, error falls with time, and the estimate/true factors F_matched and
k of every analysed bake lie within [--min-factor, --max-factor] (default
0.2..5) and F at every budget within 4x that (F alone, within the bound
itself, without python3-openimageio); 1 otherwise.
"""
# Over 500 lines: one script runs the whole error-against-time benchmark (ladders, cached references, tables), so a figure in docs/performance.md is one command.

import argparse
import csv
import hashlib
import json
import math
import os
import pathlib
import platform
import re
import shutil
import subprocess
import sys
import time

import numpy as np

_REPO = pathlib.Path(__file__).resolve().parents[2]

# Scenes without lights of their own get the constant sky and sun of
# tests/bench/bake.cpp; the Cornell box is lit by its emissive quad only.
SKY_SUN = ["--sky", "0.4,0.5,0.7", "--sun", "0.3,-1,0.2", "--sun-illuminance", "5"]
BUNDLED = {
    "cornell_box": "scenes/cornell_box.gltf",
    "foliage_instanced": "scenes/foliage_instanced.glb",
    "procedural_city": "scenes/procedural_city.glb",
}

# name, extra bake options, filter (picks the reference), what it ablates
CONFIGS = [
    ("default", [], "box", "compaction on, sorting off, Sobol, box filter"),
    ("no_compaction", ["--no-compaction"], "box", "stream compaction off"),
    ("sort_directions", ["--sort-directions"], "box", "ray-direction sorting on"),
    ("random_sequence", ["--random-sequence"], "box", "random (PCG) instead of Sobol"),
    ("gaussian_filter", ["--filter", "gaussian"], "gaussian", "Gaussian filter (1.5-texel radius)"),
]
NOT_PRESENT = [("tile_indexing", "tile-based indexing", "not present in the engine")]


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxel", default=str(_REPO / "build/client/luxel"), help="the luxel CLI")
    p.add_argument("--out", default=str(_REPO / "out/bench"), help="output folder")
    p.add_argument("--scenes", default="cornell_box,foliage_instanced",
                   help="comma-separated bundled scene names (%s) or paths" % ", ".join(BUNDLED))
    p.add_argument("--budgets", default="1,2,4,8", help="time budgets in seconds, comma-separated")
    p.add_argument("--reference-spp", type=int, default=4096, help="samples per texel of the references")
    p.add_argument("--reference-cache", default=None, help="reference cache folder (default OUT/references)")
    p.add_argument("--resolution", type=int, default=128, help="lightmap side in texels")
    p.add_argument("--bounces", type=int, default=4)
    p.add_argument("--seed", type=int, default=1, help="seed of the measured bakes (reference: seed + 1000)")
    p.add_argument("--paths-per-iteration", type=int, default=32768,
                   help="batch size of the measured bakes (small: a series point every few batches)")
    p.add_argument("--progress-interval", type=float, default=0.1, help="seconds between series points")
    p.add_argument("--configs", default=",".join(c[0] for c in CONFIGS),
                   help="comma-separated configurations (default first is required)")
    p.add_argument("--min-factor", type=float, default=0.2, help="sanity bound on estimate/true factors")
    p.add_argument("--max-factor", type=float, default=5.0)
    p.add_argument("--device", default=None, help="OpenCL device (luxel --device)")
    p.add_argument("--quick", action="store_true",
                   help="smoke run for ctest: Cornell box 32^2, budgets 0.4,0.8,1.6 s (0.2 s fell before the first progress point on a loaded machine), reference 4096 spp")
    args = p.parse_args(argv)
    if args.quick:
        args.scenes, args.budgets, args.resolution = "cornell_box", "0.4,0.8,1.6", 32
        args.paths_per_iteration, args.progress_interval = 4096, 0.05
    args.budget_list = sorted(float(b) for b in args.budgets.split(",") if b.strip())
    args.config_list = [c for c in CONFIGS if c[0] in args.configs.split(",")]
    if not args.budget_list or not args.config_list or args.config_list[0][0] != "default":
        p.error("need at least one budget and the default configuration")
    args.out = pathlib.Path(args.out).resolve()
    args.reference_cache = pathlib.Path(args.reference_cache or args.out / "references").resolve()
    return args


# ---------------------------------------------------------------- machine, git


def run_text(cmd, cwd=None):
    try:
        r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=60)
        return r.stdout.strip() if r.returncode == 0 else ""
    except (OSError, subprocess.SubprocessError):
        return ""


def machine_info(luxel):
    cpu = ""
    try:
        for line in open("/proc/cpuinfo", encoding="utf-8", errors="replace"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    lscpu = {}
    for line in run_text(["lscpu"]).splitlines():
        if ":" in line:
            k, v = line.split(":", 1)
            lscpu[k.strip()] = v.strip()
    rev = run_text(["git", "rev-parse", "HEAD"], cwd=_REPO)
    dirty = run_text(["git", "status", "--porcelain", "--untracked-files=no"], cwd=_REPO)
    return {
        "cpu_model": cpu or lscpu.get("Model name", platform.processor()),
        "hardware_threads": os.cpu_count(),
        "cores_per_socket": lscpu.get("Core(s) per socket", ""),
        "sockets": lscpu.get("Socket(s)", ""),
        "hypervisor": lscpu.get("Hypervisor vendor", ""),
        "os": "%s %s" % (platform.system(), platform.release()),
        "opencl_devices": [l.strip() for l in run_text([luxel, "devices"]).splitlines() if l.strip()],
        "git_revision": rev + ("-dirty" if rev and dirty else ""),
        "luxel_version": run_text([luxel, "--version"]),
        "python": platform.python_version(),
        "load_average_start": list(os.getloadavg()),
        "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


# --------------------------------------------------------------------- bakes


def scene_files(path):
    """The scene file plus the external files a .gltf references, for the cache key."""
    files = [path]
    if path.suffix.lower() == ".gltf":
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            doc = {}
        for key in ("buffers", "images"):
            for item in doc.get(key, []):
                uri = item.get("uri", "")
                if uri and not uri.startswith("data:"):
                    files.append(path.parent / uri)
    return files


def scene_lights(name):
    return [] if "cornell" in name.lower() else list(SKY_SUN)


def bake(args, scene, out_dir, options, log_name="bake.log"):
    """Runs `luxel bake --local`; returns (ok, message). Output and log in out_dir."""
    if out_dir.exists():
        shutil.rmtree(out_dir)
    out_dir.mkdir(parents=True)
    cmd = [args.luxel, "bake", str(scene), "--local", "--out", str(out_dir), "--quiet",
           "--resolution", str(args.resolution), "--bounces", str(args.bounces)] + options
    if args.device:
        cmd += ["--device", args.device]
    t0 = time.monotonic()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    (out_dir / log_name).write_text("$ " + " ".join(cmd) + "\n" + r.stdout + r.stderr, encoding="utf-8")
    if r.returncode != 0:
        return False, "exit %d: %s" % (r.returncode, (r.stderr or r.stdout).strip()[-400:])
    for f in ("irradiance.exr", "manifest.json", "error_series.csv"):
        if not (out_dir / f).is_file():
            return False, "missing " + f
    return True, "%.1f s wall" % wall


def traced_options(luxel):
    """Options that make a bake trace every path to its end: the radiance cache
    (kernels/bake/radiance_cache.h) is consistent but biased at finite samples, so
    references leave it out. Empty for a binary without it, or where it is off."""
    r = subprocess.run([luxel, "settings", "--json"], capture_output=True, text=True, check=True)
    cache = {s["name"]: s for s in json.loads(r.stdout)["settings"]}.get("radiance_cache")
    return [cache["flag"]] if cache and cache["default"] else []


def reference(args, name, scene, filt, version_number):
    """The cached reference bake for (scene, settings, filter); bakes it when absent."""
    return reference_with(args, name, scene, filt, version_number,
                          scene_lights(name) + traced_options(args.luxel))


def reference_with(args, name, scene, filt, version_number, options):
    """The cached reference bake for (scene, settings, filter, extra options); bakes it when absent."""
    settings = {
        "resolution": args.resolution, "bounces": args.bounces, "samples": args.reference_spp,
        "seed": args.seed + 1000, "filter": filt, "lights": options, "device": args.device,
    }
    h = hashlib.sha256()
    for f in scene_files(scene):
        h.update(f.name.encode() + b"\0")
        h.update(f.read_bytes())
    h.update(json.dumps(settings, sort_keys=True).encode())
    h.update(("luxel " + version_number).encode())
    key = h.hexdigest()[:16]
    d = args.reference_cache / ("%s-%s-%s" % (name, filt, key))
    if (d / "key.json").is_file() and (d / "irradiance.exr").is_file() and (d / "manifest.json").is_file():
        print("  reference %s (%s filter): cached %s" % (name, filt, d.name), flush=True)
        return d, True, ""
    print("  reference %s (%s filter): baking %d spp ..." % (name, filt, args.reference_spp), flush=True)
    opts = ["--samples", str(args.reference_spp), "--seed", str(args.seed + 1000), "--filter", filt]
    ok, msg = bake(args, scene, d, opts + options)
    if not ok:
        return d, False, msg
    (d / "key.json").write_text(json.dumps({"key": key, "scene": str(scene), "settings": settings,
                                            "luxel_version": version_number}, indent=1), encoding="utf-8")
    print("    %s" % msg, flush=True)
    return d, True, ""


def read_series(path):
    rows = []
    with open(path, newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            rows.append({k: float(v) if v not in ("", None) else math.nan for k, v in row.items()})
    return rows


# ------------------------------------------------------------------- analysis


def interp_loglog(ts, ys, t):
    """log-log interpolation of ys(ts) at t; nan outside the series or on a non-positive value."""
    ts, ys = np.asarray(ts, float), np.asarray(ys, float)
    ok = (ts > 0) & (ys > 0) & np.isfinite(ys)
    ts, ys = ts[ok], ys[ok]
    if len(ts) == 0 or t < ts[0] * 0.999 or t > ts[-1] * 1.001:
        return math.nan
    return float(np.exp(np.interp(math.log(t), np.log(ts), np.log(ys))))


def loglog_slope(ts, ys, lo, hi):
    ts, ys = np.asarray(ts, float), np.asarray(ys, float)
    ok = (ts >= lo * 0.999) & (ts <= hi * 1.001) & (ys > 0) & np.isfinite(ys)
    if ok.sum() < 3:
        return math.nan
    return float(np.polyfit(np.log(ts[ok]), np.log(ys[ok]), 1)[0])


def read_exr(path):
    import OpenImageIO as oiio  # python3-openimageio
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise RuntimeError("cannot open %s: %s" % (path, oiio.geterror()))
    a = np.asarray(inp.read_image(format="float"), dtype=np.float64)
    inp.close()
    return a if a.ndim == 3 else a[..., None]


def luminance(a):
    return 0.2126 * a[..., 0] + 0.7152 * a[..., 1] + 0.0722 * a[..., 2]


def reference_floor(ref_dir):
    """The reference's own noise in the units of the series: (rmse, rel_mse) from its rel_error.exr."""
    ref = read_exr(ref_dir / "irradiance.exr")
    rr = read_exr(ref_dir / "rel_error.exr")[..., 0]
    cov = ref[..., 3] > 0
    sigma = rr[cov][:, None] * ref[cov][:, :3]  # per channel, relative error of the luminance
    c = ref[cov][:, :3]
    return float(np.sqrt(np.mean(sigma ** 2))), float(np.mean(sigma ** 2 / (c ** 2 + 1e-2)))


def per_texel(bake_dir, ref_dir):
    """Per-texel estimate/true factor and the RMSE / relMSE of the final lightmap against ref_dir."""
    x = read_exr(bake_dir / "irradiance.exr")
    r = read_exr(bake_dir / "rel_error.exr")[..., 0]
    ref = read_exr(ref_dir / "irradiance.exr")
    rr = read_exr(ref_dir / "rel_error.exr")[..., 0]
    cov = x[..., 3] > 0
    d = x[cov][:, :3] - ref[cov][:, :3]
    rmse = float(np.sqrt(np.mean(d ** 2)))
    rel_mse = float(np.mean(d ** 2 / (ref[cov][:, :3] ** 2 + 1e-2)))
    y, yr = luminance(x), luminance(ref)
    m = cov & (yr > 0) & (r > 0) & (r < 1) & np.isfinite(r) & np.isfinite(rr)
    e = (y[m] - yr[m]) / yr[m]
    z_raw = e / r[m]
    z = e / np.sqrt(r[m] ** 2 + rr[m] ** 2)
    return {
        "texels": int(m.sum()),
        "k": float(1 / np.sqrt(np.mean(z ** 2))),
        "k_raw": float(1 / np.sqrt(np.mean(z_raw ** 2))),
        "k_med": float(0.6745 / np.median(np.abs(z))),
        "max_abs_z": float(np.max(np.abs(z))),
        "mean_rel_error": float(np.mean(r[m])),
        "rms_rel_error": float(np.sqrt(np.mean(r[m] ** 2))),
        # The estimate's own aggregation (mean over texels of a relative standard error) applied to the
        # true deviation: E|e| = sqrt(2/pi) sigma for a normal e, so sqrt(pi/2) mean |e| estimates the mean
        # relative standard error the engine tries to report.
        "matched_true": float(np.sqrt(np.pi / 2) * np.mean(np.abs(e))),
        "f_matched": float(np.mean(r[m]) / (np.sqrt(np.pi / 2) * np.mean(np.abs(e)))),
        "rmse": rmse,
        "rel_mse": rel_mse,
    }


def fmt(v, spec=".4g"):
    return "n/a" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


# ----------------------------------------------------------------------- main


def main(argv):
    if "--equal-error" in argv:  # the variance-reduction ablations (equal_error.py)
        import equal_error
        return equal_error.main(argv)
    args = parse_args(argv)
    if not os.access(args.luxel, os.X_OK):
        print("error: %s is not an executable" % args.luxel, file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    t_start = time.monotonic()
    machine = machine_info(args.luxel)
    m = re.search(r"(\d+\.\d+\.\d+)", machine["luxel_version"])
    version_number = m.group(1) if m else machine["luxel_version"]
    try:
        import OpenImageIO  # noqa: F401
        have_oiio = True
    except ImportError:
        have_oiio = False
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        plt = None

    budgets, t_max = args.budget_list, args.budget_list[-1]
    failures = []
    results = {"machine": machine, "settings": {
        "resolution": args.resolution, "bounces": args.bounces, "seed": args.seed,
        "reference_seed": args.seed + 1000, "reference_spp": args.reference_spp, "budgets_s": budgets,
        "paths_per_iteration": args.paths_per_iteration, "progress_interval_s": args.progress_interval,
        "quick": args.quick}, "scenes": {}}
    header = ["# luxel error_vs_time benchmark (tests/bench/error_vs_time.py)",
              "# machine: %s, %s threads, %s" % (machine["cpu_model"], machine["hardware_threads"], machine["os"]),
              "# opencl: %s" % " | ".join(machine["opencl_devices"]),
              "# git: %s  luxel: %s" % (machine["git_revision"], machine["luxel_version"]),
              "# settings: resolution %d, bounces %d, seed %d, budgets %s s, reference %d spp (seed %d)" % (
                  args.resolution, args.bounces, args.seed, ",".join("%g" % b for b in budgets),
                  args.reference_spp, args.seed + 1000),
              "# date: %s" % machine["date_utc"]]
    print("\n".join(h[2:] for h in header[1:]), flush=True)

    for scene_arg in [s.strip() for s in args.scenes.split(",") if s.strip()]:
        scene = pathlib.Path(BUNDLED.get(scene_arg, scene_arg))
        if not scene.is_absolute():
            scene = (_REPO / scene) if (_REPO / scene).exists() else scene.resolve()
        name = scene_arg if scene_arg in BUNDLED else scene.stem
        print("\n== %s (%s)" % (name, scene), flush=True)
        if not scene.is_file():
            failures.append("%s: scene %s not found" % (name, scene))
            continue
        sres = {"scene": str(scene.relative_to(_REPO) if scene.is_relative_to(_REPO) else scene),
                "lights": " ".join(scene_lights(name)) or "scene emitters only",
                "references": {}, "configs": {}}
        results["scenes"][name] = sres
        scene_dir = args.out / name
        scene_dir.mkdir(parents=True, exist_ok=True)

        refs = {}
        for filt in sorted({c[2] for c in args.config_list}):
            d, ok, msg = reference(args, name, scene, filt, version_number)
            if not ok:
                failures.append("%s: reference (%s) failed: %s" % (name, filt, msg))
                continue
            man = json.loads((d / "manifest.json").read_text(encoding="utf-8"))
            floor = reference_floor(d) if have_oiio else (math.nan, math.nan)
            refs[filt] = d
            sres["references"][filt] = {
                "dir": str(d), "seconds": man["stats"]["seconds"], "mean_spp": man["stats"]["mean_spp"],
                "error_estimate": man["stats"]["error_estimate"], "covered_texels": man["stats"]["covered_texels"],
                "floor_rmse": floor[0], "floor_sqrt_rel_mse": math.sqrt(floor[1]) if floor[1] >= 0 else math.nan,
                "floor_rel_mse": floor[1]}
        if "box" not in refs:
            continue

        series_rows = []
        for cname, copts, filt, _what in args.config_list:
            if filt not in refs:
                continue
            base = ["--seed", str(args.seed), "--paths-per-iteration", str(args.paths_per_iteration)]
            base += copts + scene_lights(name)
            # Warm-up: same kernels and launch sizes, unmeasured (program builds, PoCL JIT).
            ok, msg = bake(args, scene, scene_dir / "warmup", base + ["--samples", "0", "--time",
                                                                     "%g" % min(0.5, t_max)])
            if not ok:
                failures.append("%s/%s: warm-up bake failed: %s" % (name, cname, msg))
                continue
            bdir = scene_dir / cname
            ok, msg = bake(args, scene, bdir, base + [
                "--samples", "0", "--time", "%g" % t_max, "--progress-interval", "%g" % args.progress_interval,
                "--reference", str(refs[filt] / "irradiance.exr")])
            if not ok:
                failures.append("%s/%s: bake failed: %s" % (name, cname, msg))
                continue
            rows = read_series(bdir / "error_series.csv")
            man = json.loads((bdir / "manifest.json").read_text(encoding="utf-8"))
            bad = [r for r in rows if not all(math.isfinite(r[k]) for k in
                                              ("elapsed_s", "paths", "rel_error", "rmse", "rel_mse"))]
            if len(rows) < 2 or bad:
                failures.append("%s/%s: series has %d points, %d non-finite" % (name, cname, len(rows), len(bad)))
                continue
            ts = [r["elapsed_s"] for r in rows]
            col = lambda k: [r[k] for r in rows]  # noqa: E731
            cres = {"what": _what, "filter": filt, "random": "--random-sequence" in copts, "seconds": man["stats"]["seconds"],
                    "paths": man["stats"]["paths"], "points": len(rows), "device": man.get("device", ""),
                    "git_revision_binary": man.get("git_revision", ""), "budgets": []}
            for b in budgets:
                est = interp_loglog(ts, col("rel_error"), b)
                rmse = interp_loglog(ts, col("rmse"), b)
                relmse = interp_loglog(ts, col("rel_mse"), b)
                paths = float(np.interp(b, ts, col("paths"))) if ts[0] <= b <= ts[-1] * 1.001 else math.nan
                sq = math.sqrt(relmse) if math.isfinite(relmse) else math.nan
                cres["budgets"].append({
                    "budget_s": b, "paths": paths, "mean_spp": paths / man["stats"]["covered_texels"],
                    "estimate": est, "rmse": rmse, "sqrt_rel_mse": sq, "rel_mse": relmse,
                    "factor": est / sq if sq > 0 else math.nan, "factor_corr": math.nan})
            cres["slope_rmse"] = loglog_slope(ts, col("rmse"), budgets[0], t_max)
            cres["slope_estimate"] = loglog_slope(ts, col("rel_error"), budgets[0], t_max)
            if have_oiio:
                cres["per_texel"] = per_texel(bdir, refs[filt])
                if filt != "box":  # bias included: against the box reference too
                    cres["per_texel_vs_box"] = per_texel(bdir, refs["box"])
            bake_msg = msg
            if cname == "default":
                # The same bake stopped at each smaller budget (same seed: the state the long bake passed
                # through), for the per-texel factors along the ladder and to check the one-bake reading.
                cres["ladder"] = []
                for b in budgets[:-1]:
                    ldir = scene_dir / ("default_t%g" % b)
                    ok, msg = bake(args, scene, ldir, base + [
                        "--samples", "0", "--time", "%g" % b, "--progress-interval", "%g" % args.progress_interval,
                        "--reference", str(refs[filt] / "irradiance.exr")])
                    if not ok:
                        failures.append("%s/default at %g s: bake failed: %s" % (name, b, msg))
                        continue
                    st = json.loads((ldir / "manifest.json").read_text(encoding="utf-8"))["stats"]
                    entry = {"budget_s": b, "seconds": st["seconds"], "paths": st["paths"],
                             "estimate": st["error_estimate"], "rmse": st.get("rmse", math.nan),
                             "sqrt_rel_mse": math.sqrt(st["rel_mse"]) if "rel_mse" in st else math.nan}
                    # Same seed: the same paths give the same lightmap, so at equal paths the RMSE must
                    # agree with the long bake's series; at equal time the paths differ by the run-to-run
                    # spread of throughput.
                    entry["series_rmse_at_paths"] = interp_loglog(col("paths"), col("rmse"), st["paths"])
                    entry["series_paths_at_seconds"] = float(np.interp(st["seconds"], ts, col("paths")))
                    if have_oiio:
                        entry["per_texel"] = per_texel(ldir, refs[filt])
                    cres["ladder"].append(entry)
                last = {"budget_s": t_max, "seconds": man["stats"]["seconds"], "paths": man["stats"]["paths"],
                        "estimate": man["stats"]["error_estimate"], "rmse": man["stats"].get("rmse", math.nan),
                        "sqrt_rel_mse": math.sqrt(man["stats"].get("rel_mse", math.nan))}
                if "per_texel" in cres:
                    last["per_texel"] = cres["per_texel"]
                cres["ladder"].append(last)
            sres["configs"][cname] = cres
            for r in rows:
                series_rows.append([cname] + [r[k] for k in ("elapsed_s", "paths", "mean_spp", "min_spp",
                                                            "rel_error", "rmse", "rel_mse")])
            b_last = cres["budgets"][-1]
            print("  %-16s %s  %d points, %.3g paths; at %g s: estimate %s  rmse %s  sqrt(relMSE) %s  F %s%s" % (
                cname, bake_msg, len(rows), cres["paths"], t_max, fmt(b_last["estimate"]), fmt(b_last["rmse"]),
                fmt(b_last["sqrt_rel_mse"]), fmt(b_last["factor"], ".3f"),
                ("  k %.3f" % cres["per_texel"]["k"]) if "per_texel" in cres else ""), flush=True)
        shutil.rmtree(scene_dir / "warmup", ignore_errors=True)

        # The reference's noise: its rel_error.exr overstates it by about the per-texel factor k of the
        # same sampler (measured here at the largest budget; at the reference's higher spp k is likely
        # larger, so floor / k^2 is still an upper bound). F_corr removes it from relMSE.
        for filt, rinfo in sres["references"].items():
            k = next((c["per_texel"]["k"] for c in sres["configs"].values()
                      if c["filter"] == filt and "per_texel" in c and not c["random"]), math.nan)
            k = k if math.isfinite(k) and k > 1 else 1.0
            rinfo["k_used"] = k
            rinfo["floor_rmse_scaled"] = rinfo["floor_rmse"] / k
            rinfo["floor_sqrt_rel_mse_scaled"] = rinfo["floor_sqrt_rel_mse"] / k
            for c in sres["configs"].values():
                if c["filter"] != filt:
                    continue
                fl = rinfo["floor_rel_mse"] / (k * k)
                for x in c["budgets"]:
                    corr = x["rel_mse"] - fl
                    x["factor_corr"] = x["estimate"] / math.sqrt(corr) if corr > 0 else math.inf

        # Checks: finite, error falls with time, factors inside the sane bound.
        for cname, cres in sres["configs"].items():
            # A budget before the series' first point (a loaded machine can take longer than the
            # first budget for the first iteration) has no reading: it is reported, not failed,
            # since when the first point comes is wall-clock timing. Two budgets must remain.
            bl = [x for x in cres["budgets"]
                  if all(math.isfinite(x[k]) for k in ("estimate", "rmse", "sqrt_rel_mse", "factor"))]
            skipped = [x["budget_s"] for x in cres["budgets"] if x not in bl]
            if skipped:
                print("  %s/%s: no reading at %s s (before the series' first point)" % (
                    name, cname, ", ".join("%g" % b for b in skipped)), flush=True)
            if len(bl) < 2:
                failures.append("%s/%s: fewer than two budgets inside the series" % (name, cname))
                continue
            if len(bl) > 1 and not (bl[-1]["rmse"] < bl[0]["rmse"] and bl[-1]["estimate"] < bl[0]["estimate"]):
                failures.append("%s/%s: error does not fall between %g s and %g s" % (name, cname, budgets[0], t_max))
            # F mixes calibration with how the error is spread over texels (mean vs RMS): a few
            # heavy-tailed texels pull it far below 1 (procedural_city, random sequence: 0.12 at 1 s with
            # k = 1.00), so it gets a 4x wider bound; F_matched and k get the bound itself. Without
            # OpenImageIO F is all there is and gets the bound itself.
            lo, hi = (args.min_factor, args.max_factor) if not have_oiio else (
                args.min_factor / 4, args.max_factor * 4)
            for x in bl:
                if not lo <= x["factor"] <= hi:
                    failures.append("%s/%s: estimate/true factor F = %.3f at %g s outside [%g, %g]" % (
                        name, cname, x["factor"], x["budget_s"], lo, hi))
            pts = [(cres["budgets"][-1]["budget_s"], cres.get("per_texel"))]
            pts += [(x["budget_s"], x.get("per_texel")) for x in cres.get("ladder", [])[:-1]]
            for b, pt in pts:
                for key in ("k", "f_matched"):
                    if pt and not args.min_factor <= pt[key] <= args.max_factor:
                        failures.append("%s/%s: per-texel factor %s = %.3f at %g s outside [%g, %g]" % (
                            name, cname, key, pt[key], b, args.min_factor, args.max_factor))

        # Per-scene CSVs and plot.
        with open(scene_dir / "series.csv", "w", newline="", encoding="utf-8") as f:
            f.write("\n".join(header) + "\n# scene: %s (%s)\n" % (sres["scene"], sres["lights"]))
            w = csv.writer(f)
            w.writerow(["config", "elapsed_s", "paths", "mean_spp", "min_spp", "rel_error", "rmse", "rel_mse"])
            w.writerows(series_rows)
        with open(scene_dir / "budgets.csv", "w", newline="", encoding="utf-8") as f:
            f.write("\n".join(header) + "\n# scene: %s (%s)\n" % (sres["scene"], sres["lights"]))
            f.write("# factor = estimate / sqrt(rel_mse); factor_corr with the reference's noise removed\n")
            w = csv.writer(f)
            w.writerow(["config", "budget_s", "paths", "mean_spp", "estimate", "rmse", "sqrt_rel_mse",
                        "factor", "factor_corr"])
            for cname, cres in sres["configs"].items():
                for x in cres["budgets"]:
                    w.writerow([cname] + ["%.6g" % x[k] for k in ("budget_s", "paths", "mean_spp", "estimate",
                                                                   "rmse", "sqrt_rel_mse", "factor",
                                                                   "factor_corr")])
        if plt is not None and sres["configs"]:
            fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
            for ax, (k, label) in zip(axes, [("rel_error", "estimate (mean rel. std. error)"),
                                             ("rmse", "RMSE vs reference"),
                                             ("rel_mse", "sqrt(relMSE) vs reference")]):
                for cname in sres["configs"]:
                    pts = [r for r in series_rows if r[0] == cname]
                    i = {"rel_error": 5, "rmse": 6, "rel_mse": 7}[k]
                    ys = [math.sqrt(r[i]) if k == "rel_mse" else r[i] for r in pts]
                    lab = cname + (" (vs %s reference)" % sres["configs"][cname]["filter"]
                                   if sres["configs"][cname]["filter"] != "box" else "")
                    ax.loglog([r[1] for r in pts], ys, label=lab, lw=2.0 if cname == "default" else 1.0)
                for b in budgets:
                    ax.axvline(b, color="0.85", lw=0.8, zorder=0)
                fl = sres["references"]["box"]
                fv = {"rmse": fl.get("floor_rmse_scaled"), "rel_mse": fl.get("floor_sqrt_rel_mse_scaled")}.get(k)
                if fv and math.isfinite(fv):
                    ax.axhline(fv, color="k", ls=":", lw=1, label="box reference's noise (bound)")
                ax.set_xlabel("tracing time (s)")
                ax.set_title(label)
                ax.grid(True, which="both", alpha=0.3)
            axes[1].legend(fontsize=8)
            fig.suptitle("%s, %d^2, %d bounces, seed %d; %s; git %s" % (
                name, args.resolution, args.bounces, args.seed, machine["cpu_model"], machine["git_revision"]),
                fontsize=9)
            fig.tight_layout()
            fig.savefig(scene_dir / "error_vs_time.png", dpi=100)
            plt.close(fig)

    # Ablations and summary.
    abl = []
    for name, sres in results["scenes"].items():
        d = sres["configs"].get("default")
        if not d:
            continue
        dl = d["budgets"][-1]
        for cname, cres in sres["configs"].items():
            if cname == "default":
                continue
            cl = cres["budgets"][-1]
            row = {"scene": name, "config": cname, "what": cres["what"], "time_s": t_max,
                   "paths_ratio": cl["paths"] / dl["paths"], "rmse_ratio": cl["rmse"] / dl["rmse"],
                   "sqrt_rel_mse_ratio": cl["sqrt_rel_mse"] / dl["sqrt_rel_mse"],
                   "estimate_ratio": cl["estimate"] / dl["estimate"], "slope_rmse": cres["slope_rmse"],
                   "reference": cres["filter"]}
            abl.append(row)
            if "per_texel_vs_box" in cres and "per_texel" in d:
                pv, pd = cres["per_texel_vs_box"], d["per_texel"]
                abl.append(dict(row, config=cname + " (vs box reference, at end)", reference="box",
                                rmse_ratio=pv["rmse"] / pd["rmse"],
                                sqrt_rel_mse_ratio=math.sqrt(pv["rel_mse"] / pd["rel_mse"]),
                                estimate_ratio=math.nan, slope_rmse=math.nan,
                                paths_ratio=cres["paths"] / d["paths"]))
        for key, what, note in NOT_PRESENT:
            abl.append({"scene": name, "config": key, "what": what, "note": note})
    results["ablations"] = abl
    with open(args.out / "ablations.csv", "w", newline="", encoding="utf-8") as f:
        f.write("\n".join(header) + "\n# ratios config / default at equal tracing time (< 1: lower error)\n")
        w = csv.writer(f)
        keys = ["scene", "config", "time_s", "paths_ratio", "rmse_ratio", "sqrt_rel_mse_ratio", "estimate_ratio",
                "slope_rmse", "reference", "note"]
        w.writerow(keys)
        for r in abl:
            w.writerow([("%.4g" % r[k]) if isinstance(r.get(k), float) else r.get(k, "") for k in keys])

    machine["load_average_end"] = list(os.getloadavg())
    results["wall_s"] = time.monotonic() - t_start
    results["failures"] = failures
    results["have_openimageio"] = have_oiio
    (args.out / "machine.json").write_text(json.dumps(machine, indent=1), encoding="utf-8")
    (args.out / "summary.json").write_text(json.dumps(results, indent=1, default=str), encoding="utf-8")
    md = summary_markdown(args, results)
    (args.out / "summary.md").write_text(md, encoding="utf-8")
    print("\n" + md)
    print("wrote %s (summary.md, summary.json, machine.json, ablations.csv, <scene>/series.csv, budgets.csv, "
          "error_vs_time.png) in %.0f s" % (args.out, results["wall_s"]))
    if failures:
        print("\nFAILED:\n  " + "\n  ".join(failures), file=sys.stderr)
        return 1
    return 0


def summary_markdown(args, res):
    m = res["machine"]
    dev = next((c["device"] for s in res["scenes"].values() for c in s["configs"].values()), "")
    out = ["# Error against time (`tests/bench/error_vs_time.py`)", "",
           "- machine: %s, %s hardware threads (%s cores/socket x %s sockets%s), %s" % (
               m["cpu_model"], m["hardware_threads"], m["cores_per_socket"], m["sockets"],
               ", " + m["hypervisor"] + " guest" if m["hypervisor"] else "", m["os"]),
           "- OpenCL device: %s" % (dev or " | ".join(m["opencl_devices"])),
           "- git: %s; %s; load average %.2f at start, %.2f at end" % (
               m["git_revision"], m["luxel_version"], m["load_average_start"][0], m["load_average_end"][0]),
           "- settings: %d^2, %d bounces, seed %d, budgets %s s (read off one bake per configuration), "
           "%d paths per iteration, reference %d spp (seed %d), run took %.0f s" % (
               args.resolution, args.bounces, args.seed, ", ".join("%g" % b for b in args.budget_list),
               args.paths_per_iteration, args.reference_spp, args.seed + 1000, res["wall_s"]), ""]
    out += ["## Default configuration: error at each budget", "",
            "estimate = the engine's reference-free estimate (mean over covered texels of the relative "
            "standard error of the luminance mean); RMSE and sqrt(relMSE) against the reference, read off "
            "one %g s bake; F = estimate / sqrt(relMSE) (F_corr: the reference's noise removed); "
            "F_matched = estimate / (sqrt(pi/2) x mean over texels of |Y - Y_ref| / Y_ref) and "
            "k = 1 / RMS(z), from a bake stopped at that budget (> 1: the estimate is conservative)."
            % args.budget_list[-1], "",
            "| scene | budget s | mean spp | estimate | RMSE | sqrt(relMSE) | F | F_corr | F_matched | k |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, s in res["scenes"].items():
        d = s["configs"].get("default")
        lad = {x["budget_s"]: x.get("per_texel", {}) for x in (d or {}).get("ladder", [])}
        for x in (d["budgets"] if d else []):
            pt = lad.get(x["budget_s"], {})
            out.append("| %s | %g | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                name, x["budget_s"], fmt(x["mean_spp"], ".0f"), fmt(x["estimate"]), fmt(x["rmse"]),
                fmt(x["sqrt_rel_mse"]), fmt(x["factor"], ".2f"), fmt(x["factor_corr"], ".2f"),
                fmt(pt.get("f_matched"), ".2f"), fmt(pt.get("k"), ".2f")))
    checks = []
    for name, s in res["scenes"].items():
        d = s["configs"].get("default")
        for x in (d or {}).get("ladder", [])[:-1]:
            rel = x["rmse"] / x["series_rmse_at_paths"] - 1 if x["series_rmse_at_paths"] > 0 else math.nan
            thr = x["paths"] / x["series_paths_at_seconds"] - 1 if x["series_paths_at_seconds"] > 0 else math.nan
            checks.append("%s %g s: RMSE %+.1f %%, paths %+.1f %%" % (name, x["budget_s"], 100 * rel, 100 * thr))
    if checks:
        out += ["", "One long bake vs a bake stopped at the budget (same seed): the stopped bake's RMSE against "
                "the long bake's series at the same number of paths, and its paths against the series' at "
                "the same tracing time (run-to-run throughput): " + "; ".join(checks) + "."]
    out += ["", "References: their own noise from their rel_error.exr, divided by the per-texel k of the same "
            "sampler (still an upper bound: k grows with spp on these scenes).", "",
            "| scene | filter | spp | seconds | estimate | k used | noise RMSE | noise sqrt(relMSE) |",
            "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, s in res["scenes"].items():
        for filt, r in s["references"].items():
            out.append("| %s | %s | %.0f | %.1f | %s | %s | %s | %s |" % (
                name, filt, r["mean_spp"], r["seconds"], fmt(r["error_estimate"]), fmt(r.get("k_used"), ".2f"),
                fmt(r.get("floor_rmse_scaled")), fmt(r.get("floor_sqrt_rel_mse_scaled"))))
    out += ["", "## Estimate against true error, every configuration", "",
            "F over the budgets; at the end of the %g s bake: F_matched, k, k_raw (k without the reference's "
            "noise), k_med = 0.6745 / median |z|, where z = (Y - Y_ref) / Y_ref / sqrt(r^2 + r_ref^2) per "
            "texel. > 1: the estimate is conservative." % args.budget_list[-1], "",
            "| scene | config | F (min..max) | F_matched | k | k_raw | k_med | max \\|z\\| |",
            "|---|---|---|---:|---:|---:|---:|---:|"]
    all_f, all_m, all_k = [], [], []
    for name, s in res["scenes"].items():
        for cname, c in s["configs"].items():
            fs = [x["factor"] for x in c["budgets"]]
            all_f += fs
            pt = c.get("per_texel", {})
            for x in c.get("ladder", [{"per_texel": pt}]):
                if x.get("per_texel"):
                    all_k.append(x["per_texel"]["k"])
                    all_m.append(x["per_texel"]["f_matched"])
            out.append("| %s | %s | %s..%s | %s | %s | %s | %s | %s |" % (
                name, cname, fmt(min(fs), ".2f"), fmt(max(fs), ".2f"), fmt(pt.get("f_matched"), ".2f"),
                fmt(pt.get("k"), ".2f"), fmt(pt.get("k_raw"), ".2f"), fmt(pt.get("k_med"), ".2f"),
                fmt(pt.get("max_abs_z"), ".1f")))
    if all_f:
        out += ["", "Measured factors over all scenes, configurations and budgets: F %.2f..%.2f%s%s." % (
            min(all_f), max(all_f),
            (", F_matched %.2f..%.2f" % (min(all_m), max(all_m))) if all_m else "",
            (", per-texel k %.2f..%.2f" % (min(all_k), max(all_k))) if all_k else "")]
    out += ["", "## Ablations: error at equal time (%g s), configuration / default" % args.budget_list[-1], "",
            "< 1: lower error than the default at the same tracing time. paths = paths traced by then "
            "(throughput). slope = fitted d log RMSE / d log t over the ladder (-0.5: plain Monte Carlo).", "",
            "| scene | ablation | paths | RMSE | sqrt(relMSE) | estimate | slope | reference |",
            "|---|---|---:|---:|---:|---:|---:|---|"]
    for name, s in res["scenes"].items():
        d = s["configs"].get("default")
        if d:
            out.append("| %s | default (%s) | 1 | 1 | 1 | 1 | %s | box |" % (
                name, d["what"], fmt(d["slope_rmse"], ".2f")))
        for r in res["ablations"]:
            if r["scene"] != name:
                continue
            if "note" in r:
                out.append("| %s | %s | %s | | | | | |" % (name, r["what"], r["note"]))
                continue
            out.append("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
                name, r["config"], fmt(r["paths_ratio"], ".2f"), fmt(r["rmse_ratio"], ".2f"),
                fmt(r["sqrt_rel_mse_ratio"], ".2f"), fmt(r["estimate_ratio"], ".2f"), fmt(r["slope_rmse"], ".2f"),
                r["reference"]))
    if res["failures"]:
        out += ["", "## Failures", ""] + ["- " + f for f in res["failures"]]
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
