#!/usr/bin/env python3
"""Calibration of per-texel variance estimates of a texel's mean against its true error.

Bakes SCENE twice with the same seed and uniform sampling (--no-adaptive),
at S and at N = 2S samples per texel, so the N-sample bake's first S samples
are the S-sample bake; then, over covered texels, compares with the true
squared error of the N-sample luminance mean (against REFERENCE, a converged
irradiance.exr of the same size, e.g. from tests/bench/equal_error.py's
cache):
  - Welford: (rel_error * Y)^2 from the bake's rel_error.exr (independent samples);
  - two-point: (Y_N - Y_S)^2 S / (N - S), the denoiser's guide
    (server/engine/bake/progressive_variance.h), raw and after a 3x3 box.
Prints the sums over texels and estimate/true in quantile bins of each
estimate (1 = calibrated). docs/accuracy.md "Denoiser" quotes a run.

  variance_calibration.py --scene scenes/foliage_instanced.glb --reference REF.exr \
      --spp 64 -- --sky 0.4,0.5,0.7 --sun 0.3,-1,0.2 --sun-illuminance 5
"""
import argparse
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import error_vs_time as evt  # noqa: E402


def box3(a, mask):
    num = np.zeros_like(a)
    den = np.zeros_like(a)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            num += np.roll(np.roll(np.where(mask, a, 0.0), dy, 0), dx, 1)
            den += np.roll(np.roll(mask.astype(float), dy, 0), dx, 1)
    return num / np.maximum(den, 1)


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxel", default=str(evt._REPO / "build/client/luxel"))
    p.add_argument("--scene", required=True)
    p.add_argument("--reference", required=True, help="converged irradiance.exr of the same size")
    p.add_argument("--spp", type=int, default=64, help="S; the second bake has 2S")
    p.add_argument("--resolution", type=int, default=128)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("extra", nargs="*", help="more luxel bake options (after --)")
    a = p.parse_args(argv)
    ref = evt.read_exr(a.reference)
    with tempfile.TemporaryDirectory() as tmp:
        dirs = {}
        for n in (a.spp, 2 * a.spp):
            d = pathlib.Path(tmp) / str(n)
            subprocess.run([a.luxel, "bake", a.scene, "--local", "--out", str(d), "--quiet",
                            "--resolution", str(a.resolution), "--seed", str(a.seed), "--samples", str(n),
                            "--no-adaptive"] + a.extra, check=True, stdout=subprocess.DEVNULL)
            dirs[n] = d
        ys = evt.luminance(evt.read_exr(dirs[a.spp] / "irradiance.exr"))
        yn = evt.luminance(evt.read_exr(dirs[2 * a.spp] / "irradiance.exr"))
        rel = evt.read_exr(dirs[2 * a.spp] / "rel_error.exr")[..., 0]
    cov = ref[..., 3] > 0
    c = cov & (evt.luminance(ref) > 0)
    true2 = (yn - evt.luminance(ref)) ** 2
    s, n = float(a.spp), float(2 * a.spp)
    est = {"welford": (rel * yn) ** 2, "two-point": (yn - ys) ** 2 * s / (n - s)}
    est["two-point 3x3"] = box3(est["two-point"], cov)
    print("%s, %d^2, %d -> %d spp, %d texels" % (a.scene, a.resolution, a.spp, 2 * a.spp, c.sum()))
    print("sum of true squared errors %.4g" % true2[c].sum())
    for name, e in est.items():
        q = np.quantile(e[c], [0, .5, .9, .99, 1])
        bins = []
        for lo, hi in zip(q[:-1], q[1:]):
            m = c & (e >= lo) & (e <= hi)
            bins.append("%.2f" % (e[m].mean() / max(true2[m].mean(), 1e-30)))
        print("%-14s sum %.4g (x %.2f); estimate/true in bins 0-50 %%, 50-90, 90-99, 99-100: %s" % (
            name, e[c].sum(), e[c].sum() / true2[c].sum(), " ".join(bins)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
