#!/usr/bin/env python3
"""Compare Luxel and Blender Cycles lightmaps written by run_peer_bench.sh.

  /usr/bin/python3 tests/bench/peers/compare.py OUT

Reads OUT/<scene>/{settings.json, luxel_ref/, luxel/s<N>/, blender-<V>/,
hires/} for every scene directory, one blender-<V>/ per Cycles version V that
run_peer_bench.sh ran (PEER_BLENDERS; a blender/ directory of older runs is
read as its blender.json's version), prints Markdown tables (agreement, error
ladders, time to equal error, speed ratios) and writes OUT/summary.json (one
entry per scene and Cycles version), OUT/<scene>/errors.csv and, with
matplotlib, OUT/<scene>/error_vs_time.png. With two or more Cycles versions
the report starts with their columns side by side, and the per-version files
are errors_cycles-<V>.csv and error_vs_time_cycles-<V>.png.

Conventions (README.md next to this file):
  * both images hold irradiance E in W/m^2 (Blender's pass already x pi),
    row 0 = top = TEXCOORD_1 v = 0;
  * compared texels ("interior"): Luxel coverage alpha == 1 whose 8
    neighbours also have alpha == 1 (no chart borders, no texel shared by two
    charts), baked by Blender (alpha > 0);
  * "matched" texels: interior texels minus those where the two converged
    maps differ by more than 5 sigma and 1 % (sigma from both renderers'
    noise). Those are texels crossed by a contact-shadow edge, where Cycles'
    sub-texel jitter does not average the texel's area like Luxel's box
    filter does (shown by the 256^2 bakes in hires/, box-filtered to the
    comparison resolution);
  * the agreement is also split by the receiver's glTF material and into
    texels near a crease (world point within 5 % of the scene's extent of a
    turned surface rising above it: a wall meeting the ground, a box side)
    and the rest, with the ratio of the two ratios (texel_geometry.py
    rasterises TEXCOORD_1 for both; scenes of up to ~4e7 texel x triangle
    pairs get the crease split);
  * errors are over RGB (every channel of every compared texel):
        RMSE   = sqrt(mean((x - ref)^2))                    (W/m^2)
        relMSE = mean((x - ref)^2 / (ref^2 + 1e-2))
    against the shared reference = Luxel at settings["ref_spp"], seed 1
    (independent of the ladders: Luxel ladder seed 2, Cycles seeds 3, 1, 2).
    The reference's own noise (Luxel's rel_error.exr times the reference
    value, per texel) is subtracted from both measures; raw values are in
    errors.csv;
  * the speed ratio splits into throughput and error per sample: for a
    converging Monte Carlo estimator relMSE ~ V / spp, so time to an error e is
    spp / (samples/s) = V / (e x samples per texel per second) and
        t_Cycles / t_Luxel = (Luxel samples/s / Cycles samples/s)
                           x (V_Cycles / V_Luxel) x (N_Cycles / N_Luxel),
    V = relMSE x spp, N = texels traced,
    V being "error per sample" (geometric mean over the ladder rungs inside
    the error range both ladders cover). A sample is one path from one texel
    (Luxel: stats.paths; Cycles: baked texels x spp). A third factor is the
    number of texels each traces per spp (Luxel: every covered texel, chart
    borders included; Cycles: texels whose centre lies on a triangle):
    ratio ~ throughput x error per sample x (Cycles texels / Luxel texels).
"""
# Over 500 lines: the calibration, the matched-settings ladder and the report against both Cycles versions share one set of readers and metrics.
import csv
import json
import math
import os
import sys

import numpy as np

import texel_geometry

try:
    import OpenImageIO as oiio
except ImportError:  # pragma: no cover
    sys.exit("compare.py: needs python3-openimageio (tests/bench/peers/install-blender.sh)")

EPS = 1e-2
LUM = np.array([0.2126, 0.7152, 0.0722])


def read_exr(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit(f"cannot read {path}: {oiio.geterror()}")
    a = np.asarray(inp.read_image("float"), np.float64)
    inp.close()
    return a if a.ndim == 3 else a[..., None]


def box3(a):
    """3x3 box sum (zero outside)"""
    pad = np.pad(a, 1)
    h, w = a.shape
    return sum(pad[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3))


def interior_mask(alpha):
    full = (alpha >= 1.0 - 1e-6).astype(np.float64)
    return box3(full) > 8.5


def components(mask):
    """4-connected components of mask: label image (0 = background), count."""
    lab = np.zeros(mask.shape, np.int32)
    n = 0
    h, w = mask.shape
    for y0, x0 in zip(*np.nonzero(mask)):
        if lab[y0, x0]:
            continue
        n += 1
        stack = [(y0, x0)]
        lab[y0, x0] = n
        while stack:
            y, x = stack.pop()
            for yy, xx in ((y - 1, x), (y + 1, x), (y, x - 1), (y, x + 1)):
                if 0 <= yy < h and 0 <= xx < w and mask[yy, xx] and not lab[yy, xx]:
                    lab[yy, xx] = n
                    stack.append((yy, xx))
    return lab, n


class Ref:
    def __init__(self, d):
        self.img = read_exr(os.path.join(d, "irradiance.exr"))
        self.rgb = self.img[..., :3]
        rel = read_exr(os.path.join(d, "rel_error.exr"))[..., 0]
        self.var = (rel[..., None] * self.rgb) ** 2   # noise variance of the reference mean
        self.manifest = json.load(open(os.path.join(d, "manifest.json")))


def errors(x, ref_rgb, ref_var, mask):
    r = ref_rgb[mask]
    d2 = (x[mask][:, :3] - r) ** 2
    w = 1.0 / (r * r + EPS)
    vr = ref_var[mask]
    mse, rel = d2.mean(), (d2 * w).mean()
    return {"rmse_raw": math.sqrt(mse), "relmse_raw": rel,
            "rmse": math.sqrt(max(mse - vr.mean(), 0.0)),
            "relmse": max(rel - (vr * w).mean(), 0.0)}


def time_at(points, level):
    """log-log interpolation of the time at an error level on a ladder
    [(time, error)]; errors made monotone (running minimum in time order).
    None outside the ladder's range."""
    pts = sorted(points)
    t = np.log([p[0] for p in pts])
    e = np.minimum.accumulate(np.log([max(p[1], 1e-30) for p in pts]))
    le = math.log(level)
    if le > e[0] or le < e[-1]:
        return None
    keep = np.concatenate([[True], np.diff(e) < 0])
    return float(math.exp(np.interp(le, e[keep][::-1], t[keep][::-1])))


def speed_table(luxel, blender, nlev=5):
    """common error levels over the overlap of both ladders -> t_Cycles / t_Luxel"""
    if not luxel or not blender:
        return {"levels": [], "note": "no ladder"}
    # errors at 0 (noise subtraction leaves nothing: short quick-mode
    # references) have no place on a log scale
    el, eb = [p[1] for p in luxel if p[1] > 0], [p[1] for p in blender if p[1] > 0]
    if not el or not eb:
        return {"levels": [], "note": "no error above the reference's noise"}
    lo, hi = max(min(el), min(eb)), min(max(el), max(eb))
    if not lo < hi:
        return {"levels": [], "note": "error ranges do not overlap"}
    rows = []
    for lev in np.exp(np.linspace(math.log(hi), math.log(lo), nlev)):
        tl, tb = time_at(luxel, lev), time_at(blender, lev)
        if tl and tb:
            rows.append({"error": float(lev), "luxel_s": tl, "blender_s": tb, "ratio": tb / tl})
    gm = math.exp(np.mean([math.log(r["ratio"]) for r in rows])) if rows else None
    return {"levels": rows, "geomean_ratio": gm}


def fmt(x, nd=3):
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    if isinstance(x, (int, np.integer)):
        return str(x)
    if x == 0:
        return "0"
    a = abs(x)
    if a >= 1000 or a < 1e-3:
        return f"{x:.{nd - 1}e}"
    if a < 1:
        return f"{x:.{nd}g}"
    return f"{x:.{max(nd - 1 - int(math.log10(a)), 0)}f}"


def md_table(head, rows):
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(fmt(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def agreement(R, B, vR, vB, lab_mask, lab):
    """R, B: (n, 3) converged maps over the texels; vR, vB their noise variances"""
    d = B - R
    noise = (vR + vB).mean()
    charts = []
    for k in np.unique(lab_mask):
        m = lab_mask == k
        if m.sum() < 4:
            continue
        rl, bl = R[m] @ LUM, B[m] @ LUM
        se = math.sqrt((vR[m] @ LUM ** 2).sum() + (vB[m] @ LUM ** 2).sum()) / max(rl.sum(), 1e-30)
        ys, xs = np.nonzero(lab == k)
        charts.append({"chart": int(k), "texels": int(m.sum()), "rows": f"{ys.min()}-{ys.max()}",
                       "cols": f"{xs.min()}-{xs.max()}", "luxel_E": float(rl.mean()),
                       "blender_E": float(bl.mean()), "ratio": float(bl.sum() / max(rl.sum(), 1e-30)),
                       "ratio_se": se})
    return {"texels": int(len(R)), "mean_E_luxel": R.mean(0).tolist(), "mean_E_blender": B.mean(0).tolist(),
            "ratio_rgb": (B.sum(0) / R.sum(0)).tolist(),
            "ratio_se_rgb": (np.sqrt(vR.sum(0) + vB.sum(0)) / R.sum(0)).tolist(),
            "ratio_lum": float((B @ LUM).sum() / max((R @ LUM).sum(), 1e-30)),
            "ratio_lum_se": (math.sqrt((vR @ LUM ** 2).sum() + (vB @ LUM ** 2).sum())
                             / max((R @ LUM).sum(), 1e-30)),
            "noise_rms_rel": math.sqrt(noise) / float(R.mean()),
            "mse_over_noise": float((d * d).mean() / noise) if noise > 0 else None,
            "diff_rms_rel": math.sqrt(max((d * d).mean() - noise, 0.0)) / float(R.mean()),
            "charts": charts}


def ratio_of_ratios(a, b):
    """(a's Cycles / Luxel) / (b's), luminance, with its 1-sigma from noise"""
    ra, rb = a["ratio_lum"], b["ratio_lum"]
    r = ra / rb
    return {"ratio": r, "se": r * math.hypot(a["ratio_lum_se"] / ra, b["ratio_lum_se"] / rb)}


def split_by_geometry(st, mask, matched, ref, bhi, bvar, lab):
    """agreement per receiver material and near creases vs the rest
    (texel_geometry.py), over interior and matched texels"""
    scene = st.get("scene")
    if not scene or not os.path.isfile(scene):
        return {}
    mat_id, pos, nrm, names, tris, norms = rasterise_once(scene, st["resolution"])
    out = {"by_material": {}, "crease": {}}
    for key, m in (("interior", mask), ("matched", matched)):
        rows = []
        dark = 1e-3 * float((ref.rgb[m] @ LUM).mean())   # unlit receivers: ratios of noise
        for k in np.unique(mat_id[m]):
            mm = m & (mat_id == k)
            if mm.sum() < 4 or float((ref.rgb[mm] @ LUM).mean()) < dark:
                continue
            g = agreement(ref.rgb[mm], bhi[mm], ref.var[mm], bvar[mm], lab[mm], lab)
            g["material"] = names[k] if 0 <= k < len(names) else "(none)"
            g.pop("charts")
            rows.append(g)
        out["by_material"][key] = sorted(rows, key=lambda g: -g["texels"])
        near, d0 = texel_geometry.near_crease(pos, nrm, m, tris, norms)
        if near is None or not near.any() or near.all():
            continue
        sel = np.zeros_like(m)
        sel[m] = near
        parts = {}
        for part, mm in (("near", sel), ("rest", m & ~sel)):
            g = agreement(ref.rgb[mm], bhi[mm], ref.var[mm], bvar[mm], lab[mm], lab)
            g.pop("charts")
            parts[part] = g
        parts["distance"] = d0
        parts["near_over_rest"] = ratio_of_ratios(parts["near"], parts["rest"])
        out["crease"][key] = parts
    return out


def peer_dirs(sdir):
    """[(Cycles version, directory name)] of a scene, in version order:
    blender-<V>/, or the blender/ of a single-version run"""
    out = []
    for d in sorted(os.listdir(sdir)):
        f = os.path.join(sdir, d, "blender.json")
        if (d == "blender" or d.startswith("blender-")) and os.path.isfile(f):
            out.append((json.load(open(f))["blender_version"], d))
    return sorted(out, key=lambda vd: tuple(int(x) for x in vd[0].split(".") if x.isdigit()))


_GEOMETRY = {}


def rasterise_once(scene, res):
    """texel_geometry.rasterise, once per scene for all Cycles versions"""
    if (scene, res) not in _GEOMETRY:
        _GEOMETRY[(scene, res)] = texel_geometry.rasterise(scene, res)
    return _GEOMETRY[(scene, res)]


def hires_check(sdir, res, ref_rgb, bhi, flagged, bdir_name):
    """Luxel and Cycles at 4x the resolution, box-filtered down, on the flagged texels"""
    hd = os.path.join(sdir, "hires")
    if not os.path.isdir(os.path.join(hd, bdir_name)) or not flagged.any():
        return None
    st = json.load(open(os.path.join(hd, "settings.json")))
    k = st["resolution"] // res

    def down(a):
        return a[..., :3].reshape(res, k, res, k, 3).mean(axis=(1, 3))

    lh = down(read_exr(os.path.join(hd, "luxel", "irradiance.exr")))
    bh = down(read_exr(os.path.join(hd, bdir_name, f"blender_s{st['blender_spp']}_seed1.exr")))
    f = flagged
    vals = {"luxel": ref_rgb[f] @ LUM, "cycles": bhi[f] @ LUM,
            "luxel_hires": lh[f] @ LUM, "cycles_hires": bh[f] @ LUM}
    base = vals["luxel_hires"]

    def rel_rms(v):
        return float(np.sqrt(np.mean((v - base) ** 2)) / np.mean(base))

    return {"resolution": st["resolution"], "factor": k, "spp": st, "texels": int(f.sum()),
            "mean": {key: float(v.mean()) for key, v in vals.items()},
            "rms_vs_luxel_hires": {key: rel_rms(v) for key, v in vals.items()}}


def luxel_ladder(sdir, sub, spps, ref, mask, matched):
    """one Luxel ladder (sdir/sub/s<spp>/): the map Luxel ships by default
    (irradiance_denoised.exr where the manifest lists it, else
    irradiance.exr); engine_s = stats.seconds + the denoise step's seconds
    (denoise.seconds; older manifests only have filter_seconds)"""
    rows = []
    for spp in spps:
        dd = os.path.join(sdir, sub, f"s{spp}")
        if not os.path.isfile(os.path.join(dd, "manifest.json")):
            return []
        man = json.load(open(os.path.join(dd, "manifest.json")))
        files = {f.get("role"): f.get("path") for f in man.get("files", [])}
        dn = man.get("denoise") or {}
        denoised = "irradiance_denoised" in files
        img = read_exr(os.path.join(dd, files["irradiance_denoised"] if denoised else "irradiance.exr"))
        dn_s = (dn.get("seconds", dn.get("filter_seconds")) or 0.0) if denoised else 0.0
        row = {"spp": spp, "trace_s": man["stats"]["seconds"], "denoise_s": dn_s,
               "denoise_timing": ("seconds" if "seconds" in dn else "filter_seconds") if denoised else None,
               "denoise_method": (f"{dn.get('method', '?')} {dn.get('filter', '')}".strip()
                                  if denoised else "off"),
               "engine_s": man["stats"]["seconds"] + dn_s, "denoised": denoised,
               "wall_s": float(open(os.path.join(dd, "wall_s.txt")).read()),
               "paths": man["stats"]["paths"]}
        for key, m in (("interior", mask), ("matched", matched)):
            row[key] = errors(img, ref.rgb, ref.var, m)
        rows.append(row)
    return rows


def time_to(points, level):
    """time a ladder [(time, error)] needs to reach an error level, log-log
    along the ladder (errors made monotone: running minimum in time order).
    Returns (time, how): "interpolated"; "extrapolated" (below the ladder's
    lowest error: the line through its last two distinct rungs); "bound"
    (the ladder's cheapest rung is already at or below the level: its time,
    so the time is at most that: a Cycles / Luxel ratio from it is a lower
    bound); (None, "unreached") where the ladder stops improving."""
    pts = sorted(p for p in points if p[0] > 0)
    if not pts or not level or level <= 0:
        return None, "unreached"
    t = np.log([p[0] for p in pts])
    e = np.minimum.accumulate(np.log([max(p[1], 1e-30) for p in pts]))
    le = math.log(level)
    if le >= e[0]:
        return float(math.exp(t[0])), "bound" if le > e[0] else "interpolated"
    keep = np.concatenate([[True], np.diff(e) < 0])
    tk, ek = t[keep], e[keep]
    if le >= ek[-1]:
        return float(math.exp(np.interp(le, ek[::-1], tk[::-1]))), "interpolated"
    if len(tk) < 2:
        return None, "unreached"
    slope = (tk[-1] - tk[-2]) / (ek[-1] - ek[-2])   # d log t / d log e (< 0)
    return float(math.exp(tk[-1] + slope * (le - ek[-1]))), "extrapolated"


GOAL_SPP = 64      # the goal's target: Cycles' raw error at this many spp
GOAL_RATIO = 5.0   # the goal: Cycles time / Luxel time >= this on every scene
OIDN_SPP = (4, 16, 64)


def rung(rows, spp, seed=3):
    """the ladder rung (seed 3: Cycles' ladder) of spp samples"""
    return next((r for r in rows if r["spp"] == spp and r["seed"] == seed), None)


def versus(target, t_cycles, lux, key="engine_s"):
    """Luxel's time along a ladder to reach each of Cycles' errors (matched
    texels: relMSE and RMSE) against Cycles' time"""
    out = {"cycles_s": t_cycles}
    for meas in ("relmse", "rmse"):
        lv = target["matched"][meas]
        tl, how = time_to([(r[key], r["matched"][meas]) for r in lux], lv) if lux else (None, "no ladder")
        out[meas] = {"error": lv, "luxel_s": tl, "how": how,
                     "ratio": t_cycles / tl if tl else None}
    return out


def goal_figures(lux, lux_raw, bl, bl_dn):
    """(a) the goal figure: Luxel default's engine time to Cycles' raw
    64-spp error vs Cycles' bake call at 64 spp; (b) the same, Luxel raw;
    (c) Luxel default against Cycles + OIDN at its 4-, 16-, 64-spp errors;
    (d) end to end at (a)'s target; (e) the denoisers' own seconds"""
    c64 = rung(bl, GOAL_SPP)
    if c64 is None:
        return {"note": f"Cycles ladder has no {GOAL_SPP}-spp rung (seed 3)"}
    g = {"target_spp": GOAL_SPP, "target": {m: c64["matched"][m] for m in ("relmse", "rmse")},
         "default": versus(c64, c64["bake_s"], lux),
         "raw": versus(c64, c64["bake_s"], lux_raw) if lux_raw else None,
         "end_to_end": versus(c64, c64["cold_s"], lux, "wall_s"),
         "oidn": {}}
    for spp in OIDN_SPP:
        d = rung(bl_dn, spp)
        if d is not None:
            g["oidn"][str(spp)] = versus(d, d["bake_s"], lux)
            g["oidn"][str(spp)]["cycles_denoise_s"] = d["denoise_s"]
    d64 = rung(bl_dn, GOAL_SPP)
    if d64 is not None:   # Cycles + OIDN end to end: start, import, setup, bake, denoise
        g["oidn_end_to_end"] = versus(d64, d64["cold_s"], lux, "wall_s")
    dn = [r["denoise_s"] for r in lux if r["denoised"]]
    g["filter"] = {"luxel_denoise_s": {"min": min(dn), "median": float(np.median(dn)), "max": max(dn)}
                   if dn else None,
                   "luxel_denoise_timing": next((r["denoise_timing"] for r in lux if r["denoised"]), None),
                   "luxel_denoise_method": next((r["denoise_method"] for r in lux if r["denoised"]), "off"),
                   "cycles_denoise_s": ({"min": min(r["denoise_s"] for r in bl_dn),
                                         "median": float(np.median([r["denoise_s"] for r in bl_dn])),
                                         "max": max(r["denoise_s"] for r in bl_dn)} if bl_dn else None)}
    g["met"] = {m: verdict(g["default"][m]) for m in ("relmse", "rmse")}
    g["met"]["both"] = ("MET" if all(g["met"][m] == "MET" for m in ("relmse", "rmse")) else
                        "NOT MET" if any(g["met"][m] == "NOT MET" for m in ("relmse", "rmse"))
                        else "UNDETERMINED")
    return g


def verdict(v):
    """MET / NOT MET for ratio >= GOAL_RATIO; a lower bound below it
    (Luxel's cheapest rung already beats the target) is UNDETERMINED"""
    r = v["ratio"]
    if r is None:
        return "NOT MET"
    if r >= GOAL_RATIO:
        return "MET"
    return "UNDETERMINED" if v["how"] == "bound" else "NOT MET"


def analyse(sdir, version, bdir_name, tag):
    """one scene against one Cycles version (its bakes in sdir/bdir_name);
    tag: "" or "_cycles-<version>", the suffix of its errors.csv and plot"""
    st = json.load(open(os.path.join(sdir, "settings.json")))
    name = st["name"]
    ref = Ref(os.path.join(sdir, "luxel_ref"))
    bdir = os.path.join(sdir, bdir_name)
    bj = json.load(open(os.path.join(bdir, "blender.json")))
    hi_spp = st["blender_hi"]
    b1 = read_exr(os.path.join(bdir, f"blender_s{hi_spp}_seed1.exr"))
    b2 = read_exr(os.path.join(bdir, f"blender_s{hi_spp}_seed2.exr"))
    mask = interior_mask(ref.img[..., 3]) & (b1[..., 3] > 0) & (b2[..., 3] > 0)
    covered = int((ref.img[..., 3] > 0).sum())

    # ---- converged maps: agreement ---------------------------------------
    bhi = 0.5 * (b1[..., :3] + b2[..., :3])
    bvar = (b1[..., :3] - b2[..., :3]) ** 2 / 4.0        # var of bhi, 1-dof estimate per texel
    # flag texels whose difference exceeds the noise: sigma^2 from a 3x3
    # neighbourhood average of Cycles' variance (9 dof) plus Luxel's estimate
    m_f = mask.astype(np.float64)
    bvar_l = bvar @ LUM ** 2
    bvar_s = box3(bvar_l * m_f) / np.maximum(box3(m_f), 1)
    sig = np.sqrt(bvar_s + ref.var @ LUM ** 2)
    dl = np.abs((bhi - ref.rgb) @ LUM)
    flagged = mask & (dl > 5 * sig) & (dl > 0.01 * (ref.rgb @ LUM))
    matched = mask & ~flagged
    lab, _ = components(mask)
    agree = {"texels_covered": covered, "ref_spp": st["ref_spp"], "blender_spp": f"2 x {hi_spp}",
             "flagged": int(flagged.sum())}
    for key, m in (("interior", mask), ("matched", matched)):
        agree[key] = agreement(ref.rgb[m], bhi[m], ref.var[m], bvar[m], lab[m], lab)
    agree["hires"] = hires_check(sdir, st["resolution"], ref.rgb, bhi, flagged, bdir_name)
    agree.update(split_by_geometry(st, mask, matched, ref, bhi, bvar, lab))

    # ---- ladders ----------------------------------------------------------
    # Luxel as it ships (luxel/: the denoised map where the manifest lists
    # one) and raw (luxel_raw/: --denoise off; absent in older runs)
    lux = luxel_ladder(sdir, "luxel", st["luxel_ladder"], ref, mask, matched)
    lux_raw = luxel_ladder(sdir, "luxel_raw", st["luxel_ladder"], ref, mask, matched)
    bl, bl_dn = [], []
    cold = (bj["startup_s"] or 0.0) + bj["import_s"] + bj["setup_s"]
    for b in bj["bakes"]:
        img = read_exr(os.path.join(bdir, b["file"]))
        row = {"spp": b["samples"], "seed": b["seed"], "bake_s": b["seconds"],
               "cold_s": cold + b["seconds"], "texels": int((img[..., 3] > 0).sum())}
        for key, m in (("interior", mask), ("matched", matched)):
            row[key] = errors(img, ref.rgb, ref.var, m)
        if b["seed"] not in (1, 2):   # independent of Cycles' converged map (seeds 1, 2)
            row["own"] = errors(img, bhi, bvar, mask)
        bl.append(row)
        if b.get("denoised_file"):   # Cycles + OIDN: the bake, then the user's denoise
            dimg = read_exr(os.path.join(bdir, b["denoised_file"]))
            drow = {"spp": b["samples"], "seed": b["seed"], "bake_s": b["seconds"] + b["denoise_s"],
                    "denoise_s": b["denoise_s"], "cold_s": cold + b["seconds"] + b["denoise_s"],
                    "texels": row["texels"]}
            for key, m in (("interior", mask), ("matched", matched)):
                drow[key] = errors(dimg, ref.rgb, ref.var, m)
            bl_dn.append(drow)

    speed = {}
    goal = None
    if lux and bl:
        # engine_s: Luxel's trace seconds + its denoise step (default ladder)
        for sel in ("interior", "matched"):
            for meas in ("relmse", "rmse"):
                speed[f"engine_{sel}_{meas}"] = speed_table(
                    [(r["engine_s"], r[sel][meas]) for r in lux], [(r["bake_s"], r[sel][meas]) for r in bl])
            speed[f"end_to_end_{sel}_relmse"] = speed_table(
                [(r["wall_s"], r[sel]["relmse"]) for r in lux], [(r["cold_s"], r[sel]["relmse"]) for r in bl])
        if lux_raw:
            speed["raw_engine_matched_relmse"] = speed_table(
                [(r["engine_s"], r["matched"]["relmse"]) for r in lux_raw],
                [(r["bake_s"], r["matched"]["relmse"]) for r in bl])
        if bl_dn:
            speed["oidn_engine_matched_relmse"] = speed_table(
                [(r["engine_s"], r["matched"]["relmse"]) for r in lux],
                [(r["bake_s"], r["matched"]["relmse"]) for r in bl_dn])
        # the samples/s x error-per-sample split holds for converging
        # estimators: raw against raw where the raw ladder exists
        speed["split"] = split(lux_raw or lux, bl, speed.get("raw_engine_matched_relmse")
                               if lux_raw else speed["engine_matched_relmse"])
        speed["split"]["luxel_ladder"] = "raw (--denoise off)" if lux_raw else "default"
        speed["own_relmse"] = speed_table(
            [(r["trace_s"], r["interior"]["relmse"]) for r in (lux_raw or lux)],
            [(r["bake_s"], r["own"]["relmse"]) for r in bl if "own" in r])
        goal = goal_figures(lux, lux_raw, bl, bl_dn)
        write_csv(sdir, lux, bl, tag, lux_raw, bl_dn)
        plot(sdir, name, st, lux, bl, version, tag, lux_raw, bl_dn)
    return {"name": name, "cycles_version": version, "settings": st, "agreement": agree,
            "luxel": lux, "luxel_raw": lux_raw, "blender": bl, "blender_oidn": bl_dn, "goal": goal,
            "cycles_denoise": bj.get("denoise"),
            "blender_overheads": {"startup_s": bj["startup_s"], "import_s": bj["import_s"],
                                  "setup_s": bj["setup_s"], "warmup_s": bj.get("warmup_s")},
            "luxel_ref_seconds": ref.manifest["stats"]["seconds"], "speed": speed,
            "triangles": bj.get("triangles"),
            "cycles_settings": {k: bj.get(k) for k in ("sampling_pattern", "use_light_tree", "use_guiding",
                                                       "as_module", "exr_writer", "threads")},
            "lights": ", ".join(x.get('type', 'SUN').lower() for x in bj.get("lights", [])) or None,
            "luxel_features": ref.manifest.get("features")}


def split(lux, bl, table):
    """samples/s and error per sample (relMSE x spp, matched texels) of each
    ladder, over the rungs inside the error range of the speed table"""
    levels = [lv["error"] for lv in table["levels"]]
    lo, hi = (min(levels), max(levels)) if levels else (0.0, math.inf)

    def gm(v):
        v = [x for x in v if x > 0]
        return math.exp(np.mean(np.log(v))) if v else None

    def pick(rows, rate, texels):
        inside = [r for r in rows if lo / 2 <= r["matched"]["relmse"] <= hi * 2] or rows
        return {"samples_per_s": gm([rate(r) for r in inside]),
                "relmse_x_spp": gm([r["matched"]["relmse"] * r["spp"] for r in inside]),
                "texels": gm([texels(r) for r in inside]),
                "rungs": [r["spp"] for r in inside]}

    out = {"luxel": pick(lux, lambda r: r["paths"] / r["trace_s"], lambda r: r["paths"] / r["spp"]),
           "cycles": pick(bl, lambda r: r["texels"] * r["spp"] / r["bake_s"], lambda r: r["texels"])}
    L, C = out["luxel"], out["cycles"]
    if L["samples_per_s"] and C["samples_per_s"] and L["relmse_x_spp"] and C["relmse_x_spp"]:
        out["throughput_ratio"] = L["samples_per_s"] / C["samples_per_s"]
        out["error_per_sample_ratio"] = C["relmse_x_spp"] / L["relmse_x_spp"]
        # texels traced per sample per texel: Luxel traces every covered texel
        # (chart borders included), Cycles the texels whose centre is on a triangle
        out["texel_ratio"] = C["texels"] / L["texels"]
    return out


def write_csv(sdir, lux, bl, tag, lux_raw=(), bl_dn=()):
    """renderer luxel: its default (denoised) map, seconds = trace + denoise;
    luxel_raw: --denoise off; cycles_oidn: seconds = bake + denoise"""
    with open(os.path.join(sdir, f"errors{tag}.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["renderer", "spp", "seed", "seconds_engine", "seconds_end_to_end", "texels",
                    "rmse", "relmse", "rmse_raw", "relmse_raw", "matched_rmse", "matched_relmse",
                    "relmse_vs_own_converged", "denoise_seconds"])
        for label, rows in (("luxel", lux), ("luxel_raw", lux_raw)):
            for r in rows:
                i, m = r["interior"], r["matched"]
                w.writerow([label, r["spp"], 2, r["engine_s"], r["wall_s"], "", i["rmse"], i["relmse"],
                            i["rmse_raw"], i["relmse_raw"], m["rmse"], m["relmse"], "", r["denoise_s"]])
        for label, rows in (("cycles", bl), ("cycles_oidn", bl_dn)):
            for r in rows:
                i, m = r["interior"], r["matched"]
                w.writerow([label, r["spp"], r["seed"], r["bake_s"], r["cold_s"], r["texels"],
                            i["rmse"], i["relmse"], i["rmse_raw"], i["relmse_raw"], m["rmse"], m["relmse"],
                            r["own"]["relmse"] if "own" in r else "", r.get("denoise_s", "")])


def plot(sdir, name, st, lux, bl, version, tag, lux_raw=(), bl_dn=()):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for sel, ls in (("matched", "-"), ("interior", "--")):
        ax.loglog([r["engine_s"] for r in lux], [r[sel]["relmse"] for r in lux], "o" + ls, color="C0",
                  label=f"Luxel default, trace + denoise ({sel})")
        ax.loglog([r["bake_s"] for r in bl], [r[sel]["relmse"] for r in bl], "s" + ls, color="C1",
                  label=f"Cycles {version}, bake call ({sel})")
    if lux_raw:
        ax.loglog([r["engine_s"] for r in lux_raw], [r["matched"]["relmse"] for r in lux_raw], "^-",
                  color="C4", label="Luxel raw, trace (matched)")
    if bl_dn:
        ax.loglog([r["bake_s"] for r in bl_dn], [r["matched"]["relmse"] for r in bl_dn], "v-",
                  color="C5", label=f"Cycles {version} + OIDN, bake + denoise (matched)")
    ax.loglog([r["wall_s"] for r in lux], [r["matched"]["relmse"] for r in lux], "o:", color="C2",
              label="Luxel, process wall (matched)")
    ax.loglog([r["cold_s"] for r in bl], [r["matched"]["relmse"] for r in bl], "s:", color="C3",
              label=f"Cycles {version}, + start and import (matched)")
    ax.set_xlabel("seconds")
    ax.set_ylabel("relMSE vs Luxel reference")
    ax.set_title(f"{name}: {st['resolution']}², {st['bounces']} bounces")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(sdir, f"error_vs_time{tag}.png"), dpi=100)
    plt.close(fig)


def version_key(v):
    return tuple(int(x) if x.isdigit() else 0 for x in v.split("."))


CALIBRATION = ("sky_plane", "lights_plane")
CAL_TOL = 0.005   # |Cycles / Luxel - 1| allowed beyond 5 sigma of noise


def calibration(res, versions):
    """per Cycles version: the calibration scenes' Cycles / Luxel ratios
    (interior texels: every channel, and every chart's luminance) and
    whether each lies within CAL_TOL + 5 sigma of 1. A version whose
    calibration fails (or did not run) has ratios that do not count."""
    out = {}
    for v in versions:
        rows, ok = [], True
        for r in res:
            if r["cycles_version"] != v or r["name"] not in CALIBRATION:
                continue
            g = r["agreement"]["interior"]
            checks = [(rt, se) for rt, se in zip(g["ratio_rgb"], g["ratio_se_rgb"])]
            checks += [(c["ratio"], c["ratio_se"]) for c in g["charts"]]
            passed = all(abs(rt - 1.0) <= CAL_TOL + 5.0 * se for rt, se in checks)
            ok &= passed
            rows.append({"scene": r["name"], "ratio_rgb": g["ratio_rgb"],
                         "charts": [c["ratio"] for c in g["charts"]], "pass": passed})
        out[v] = {"scenes": rows, "pass": ok and len(rows) == len(CALIBRATION)}
    return out


def calibration_table(cal):
    rows = []
    for v, c in cal.items():
        for x in c["scenes"]:
            rows.append([v, x["scene"], " / ".join(f"{t:.4f}" for t in x["ratio_rgb"]),
                         " / ".join(f"{t:.4f}" for t in x["charts"]), "pass" if x["pass"] else "**FAIL**"])
        if len(c["scenes"]) < len(CALIBRATION):
            rows.append([v, "(not run: " + ", ".join(n for n in CALIBRATION
                                                     if n not in [x["scene"] for x in c["scenes"]]) + ")",
                         "-", "-", "**no calibration**"])
    return ("### Calibration: Cycles / Luxel on the closed-form scenes\n\n"
            f"Interior texels, converged maps; pass: every channel and every chart within "
            f"{CAL_TOL:.1%} + 5σ of 1. A version that does not pass (or was not calibrated in this "
            "run) has time ratios that do not count.\n\n"
            + md_table(["Cycles", "scene", "R / G / B", "per chart (luminance)", "calibration"], rows)
            + "\n")


def side_by_side(res, versions, cal):
    """every Cycles version in one table per scene: time to equal error
    (matched texels) in the engine and end to end, at one common error level"""
    rows = []
    names = []
    for r in res:
        if r["name"] not in names:
            names.append(r["name"])
    for name in names:
        per = {r["cycles_version"]: r for r in res if r["name"] == name}
        if not all((per.get(v, {}).get("speed") or {}).get("engine_matched_relmse", {}).get("levels")
                   for v in versions):
            continue
        row = [name]
        for kind, lx, bx in (("engine", "engine_s", "bake_s"), ("end_to_end", "wall_s", "cold_s")):
            # one error level inside every version's common range with Luxel
            lo = max(min(lv["error"] for lv in per[v]["speed"][f"{kind}_matched_relmse"]["levels"] or [{"error": math.inf}])
                     for v in versions)
            hi = min(max(lv["error"] for lv in per[v]["speed"][f"{kind}_matched_relmse"]["levels"] or [{"error": 0.0}])
                     for v in versions)
            if not lo <= hi:
                row += ["-"] * (2 + 2 * len(versions))
                continue
            level = math.sqrt(lo * hi)
            first = per[versions[0]]
            tl = time_at([(x[lx], x["matched"]["relmse"]) for x in first["luxel"]], level)
            row += [level, tl]
            for v in versions:
                tb = time_at([(x[bx], x["matched"]["relmse"]) for x in per[v]["blender"]], level)
                gm = per[v]["speed"][f"{kind}_matched_relmse"]["geomean_ratio"]
                row += [tb, f"{tb / tl:.2f} ({gm:.2f})" if tb and tl else "-"]
        rows.append(row)
    if not rows:
        return ""
    head = ["scene"]
    for kind in ("engine", "e2e"):
        head += [f"{kind} relMSE", f"Luxel {kind} s"]
        for v in versions:
            mark = "" if cal[v]["pass"] else " (not calibrated)"
            head += [f"Cycles {v}{mark} {kind} s", f"{v} ratio (geo. mean)"]
    return ("### Cycles versions side by side: time to equal relMSE (matched texels)\n\n"
            "At one error level per scene inside the range every Cycles ladder shares with "
            "Luxel's (the geometric middle of the common range). Engine: Luxel default's trace + denoise seconds vs "
            "one Cycles bake call (bpy.ops.object.bake); e2e: Luxel process wall vs Blender start "
            "(3.4.1: the blender binary; 5.0.1: `import bpy`) + import + setup + bake call. Ratio: "
            "Cycles / Luxel at that level (> 1: Luxel faster), in brackets the geometric mean over "
            "the five levels of that version's own table below. Cycles settings per version: "
            + "; ".join(f"{v}: " + ", ".join(f"{k} {val}" for k, val in
                                              next(r for r in res if r["cycles_version"] == v)
                                              ["cycles_settings"].items() if val is not None)
                        for v in versions)
            + ".\n\n" + md_table(head, rows) + "\n")


def summary(res):
    """one row per scene with a ladder: the headline numbers"""
    rows = []
    for r in res:
        sp = r.get("speed") or {}
        if not sp.get("engine_matched_relmse", {}).get("levels"):
            continue
        st = r["settings"]
        eng = sp["engine_matched_relmse"]
        mid = eng["levels"][len(eng["levels"]) // 2]
        e2e = sp["end_to_end_matched_relmse"]
        e2e_mid = min(e2e["levels"], key=lambda lv: abs(math.log(lv["error"] / mid["error"]))) \
            if e2e["levels"] else None
        spl = sp["split"]
        rows.append([r["name"], f"{st['resolution']}²", r.get("triangles") or "-", mid["error"],
                     mid["blender_s"], mid["luxel_s"], f"{eng['geomean_ratio']:.2f}",
                     e2e_mid["blender_s"] if e2e_mid else "-", e2e_mid["luxel_s"] if e2e_mid else "-",
                     f"{e2e['geomean_ratio']:.2f}" if e2e["levels"] else "-",
                     spl["cycles"]["samples_per_s"] / 1e6, spl["luxel"]["samples_per_s"] / 1e6,
                     spl["cycles"]["relmse_x_spp"], spl["luxel"]["relmse_x_spp"],
                     f"{spl.get('throughput_ratio', 0):.2f} x {spl.get('error_per_sample_ratio', 0):.2f}"
                     f" x {spl.get('texel_ratio', 0):.2f}"])
    if not rows:
        return ""
    return ("### Summary: time to equal relMSE (matched texels), Cycles vs Luxel\n\n"
            "Engine: Luxel default's trace + denoise seconds vs one Cycles bake call (raw); end to end: Luxel process wall "
            "vs Blender start + import + setup + bake call. Both at the middle one of the five "
            "common error levels; the ratio columns are the geometric mean over all five "
            "(Cycles time / Luxel time, > 1: Luxel faster). Samples/s: paths "
            "from texels per second in the engine; error per sample: relMSE x spp (lower is "
            "better); these and the split are from Luxel's raw ladder where it ran (the split holds for "
            "converging estimators). Split: ratio ≈ (Luxel / Cycles samples/s) x (Cycles / Luxel error per "
            "sample) x (texels Cycles bakes / texels Luxel bakes).\n\n"
            + md_table(["scene", "size", "triangles", "relMSE", "Cycles s", "Luxel s",
                        "engine ratio", "Cycles e2e s", "Luxel e2e s", "e2e ratio",
                        "Cycles Msamples/s", "Luxel Msamples/s", "Cycles relMSE·spp",
                        "Luxel relMSE·spp", "split: throughput x error/sample x texels"], rows) + "\n")


def ratio_cell(v):
    """'12.3' / '≥ 12.3' (bound) / '12.3 (extrap.)' / '-' for one versus() entry"""
    if not v or v.get("ratio") is None:
        return "-" if not v else f"- ({v.get('how')})"
    r = f"{v['ratio']:.2f}"
    return {"bound": f"≥ {r}", "extrapolated": f"{r} (extrap.)"}.get(v["how"], r)


def goal_table(res, versions, cal):
    """the goal figures at the top of the report: per scene and Cycles version"""
    rows, filt, verdicts = [], [], []
    for r in res:
        g = r.get("goal")
        if not g or "default" not in g:
            continue
        v = r["cycles_version"]
        d, raw, e2e = g["default"], g.get("raw") or {}, g["end_to_end"]
        oi = g.get("oidn", {})
        rows.append([r["name"], v + ("" if cal[v]["pass"] else " ¹"), g["target"]["relmse"], g["target"]["rmse"],
                     d["cycles_s"], d["relmse"]["luxel_s"], ratio_cell(d["relmse"]), ratio_cell(d["rmse"]),
                     ratio_cell(raw.get("relmse")), ratio_cell(raw.get("rmse")),
                     *[ratio_cell(oi.get(str(n), {}).get("relmse")) if str(n) in oi else "n/a"
                       for n in OIDN_SPP],
                     f"{fmt(e2e['cycles_s'])} / {fmt(e2e['relmse']['luxel_s'])} = {ratio_cell(e2e['relmse'])}",
                     (f"{fmt(g['oidn_end_to_end']['cycles_s'])} / {fmt(g['oidn_end_to_end']['relmse']['luxel_s'])}"
                      f" = {ratio_cell(g['oidn_end_to_end']['relmse'])}") if g.get("oidn_end_to_end") else "n/a",
                     f"**{g['met']['both']}**" + ("" if g["met"]["relmse"] == g["met"]["rmse"] else
                                                 f" (relMSE {g['met']['relmse']}, RMSE {g['met']['rmse']})")])
        f = g["filter"]
        ld, cd = f["luxel_denoise_s"], f["cycles_denoise_s"]
        filt.append([r["name"], v, f["luxel_denoise_method"],
                     f"{fmt(ld['median'])} ({fmt(ld['min'])} .. {fmt(ld['max'])})" if ld else "-",
                     f["luxel_denoise_timing"] or "-",
                     f"{fmt(cd['median'])} ({fmt(cd['min'])} .. {fmt(cd['max'])})" if cd else
                     (r.get("cycles_denoise") and "-") or "no OIDN in this Blender"])
        verdicts.append((r["name"], v, g["met"]["both"]))
    if not rows:
        return ""
    per_v = []
    for v in versions:
        vs = [x[2] for x in verdicts if x[1] == v]
        if vs:
            per_v.append(f"Cycles {v}: **{'MET' if all(x == 'MET' for x in vs) else 'NOT MET'}** "
                         f"({sum(x == 'MET' for x in vs)} of {len(vs)} scenes)")
    uncal = [v for v in versions if not cal[v]["pass"]]
    note = (f"\n¹ Cycles {', '.join(uncal)}: not calibrated in this run (sky_plane and lights_plane not run "
            "or not passing); the figures stand as measured, the calibration of an earlier run applies.\n"
            if uncal else "")
    return ("### Goal: Luxel (default, denoised) at Cycles' raw 64-spp error, ≥ 5x faster\n\n"
            f"Target: Cycles' raw bake at {GOAL_SPP} spp (seed 3): its relMSE and RMSE on the matched "
            "texels against the shared Luxel reference (raw, converged). Luxel's time to reach it: "
            "log-log interpolation along Luxel's ladder (\"extrap.\": past its last rung; \"≥\": Luxel's "
            "cheapest rung is already below the target, so the ratio is a lower bound). Ratio = Cycles "
            "time / Luxel time. Engine times: Luxel default = trace + denoise step (manifest "
            "stats.seconds + denoise.seconds), Luxel raw (`--denoise off`) = trace, Cycles = one bake "
            "call, Cycles + OIDN = bake call + Open Image Denoise (RT, hdr, colour only) on the bake. "
            "End to end: Luxel process wall vs Blender start + glTF import + setup + bake (+ denoise). "
            f"Goal: ratio ≥ {GOAL_RATIO:g} (relMSE and RMSE) on every scene against each version.\n\n"
            + md_table(["scene", "Cycles", "target relMSE", "target RMSE", "Cycles 64 spp s",
                        "Luxel default s (relMSE)", "**goal ratio relMSE**", "goal ratio RMSE",
                        "raw vs raw relMSE", "raw vs raw RMSE",
                        *[f"vs Cycles+OIDN {n} spp (relMSE)" for n in OIDN_SPP],
                        "end to end: Cycles 64 / Luxel s = ratio", "e2e vs Cycles+OIDN 64", "5x goal"], rows)
            + "\n" + note + "\n" + "; ".join(per_v) + "\n\n"
            "Denoise filter's own cost (seconds per bake, median (min .. max) over the ladder): Luxel's "
            "whole denoise step (manifest denoise.seconds; filter_seconds where an older manifest lacks "
            "it), Cycles' OIDN call (blender.json denoise_s).\n\n"
            + md_table(["scene", "Cycles", "Luxel denoiser", "Luxel denoise s", "Luxel timing field",
                        "Cycles OIDN s"], filt) + "\n")


def report(res):
    versions = sorted({r["cycles_version"] for r in res}, key=version_key)
    cal = calibration(res, versions)
    out = [goal_table(res, versions, cal), calibration_table(cal)]
    out += [side_by_side(res, versions, cal)] if len(versions) > 1 else []
    for v in versions:
        part = [r for r in res if r["cycles_version"] == v]
        s = summary(part)
        if s and len(versions) > 1:
            s = s.replace("### Summary:", f"### Cycles {v}, summary:", 1)
        if s and not cal[v]["pass"]:
            s = s.replace("\n\n", f"\n\n**Cycles {v} is not calibrated in this run: these ratios do "
                          "not count.**\n\n", 1)
        out.append(s)
    for r in res:
        st, a = r["settings"], r["agreement"]
        against = f" (Cycles {r['cycles_version']})" if len(versions) > 1 else ""
        out.append(f"\n### {r['name']}{against}: {st['resolution']}², {st['bounces']} bounces, "
                   f"sky {st['sky'] or 'none'}, sun {st.get('sun') or 'none'}, "
                   f"{r.get('triangles') or '?'} triangles, lights: {r.get('lights') or 'none'}\n")
        out.append(f"Reference: Luxel {a['ref_spp']} spp, seed 1 ({fmt(r['luxel_ref_seconds'])} s "
                   f"trace). Cycles converged: {a['blender_spp']} spp (seeds 1 and 2, averaged). "
                   f"Texels: {a['texels_covered']} covered, {a['interior']['texels']} interior, "
                   f"{a['flagged']} of them flagged (> 5σ and > 1 % apart), "
                   f"{a['matched']['texels']} matched.\n")
        rows = []
        for sel in ("interior", "matched"):
            g = a[sel]
            for i, c in enumerate("RGB"):
                rows.append([sel if i == 0 else "", c, g["mean_E_luxel"][i], g["mean_E_blender"][i],
                             f"{g['ratio_rgb'][i]:.4f} ± {g['ratio_se_rgb'][i]:.4f}",
                             f"{g['mse_over_noise']:.2f}" if i == 0 else "",
                             f"{100 * g['diff_rms_rel']:.2f} %" if i == 0 else ""])
        out.append(md_table(["texels", "ch.", "mean E Luxel (W/m²)", "mean E Cycles",
                             "Cycles / Luxel ± 1σ", "MSD / noise var.", "RMS diff. beyond noise"],
                            rows))
        charts = a["interior"]["charts"]
        if len(charts) > 24:   # big atlases: the 24 charts with most texels
            charts = sorted(sorted(charts, key=lambda c: -c["texels"])[:24], key=lambda c: c["chart"])
        if len(charts) > 1:
            out.append(f"\nPer chart (interior texels, luminance; {len(charts)} of "
                       f"{len(a['interior']['charts'])} charts):\n")
            out.append(md_table(["chart", "texels", "rows", "cols", "E Luxel", "E Cycles",
                                 "Cycles / Luxel ± 1σ"],
                                [[c["chart"], c["texels"], c["rows"], c["cols"], c["luxel_E"],
                                  c["blender_E"], f"{c['ratio']:.4f} ± {c['ratio_se']:.4f}"]
                                 for c in charts]))
        for sel, rows in a.get("by_material", {}).items():
            if len(rows) < 2:
                continue
            out.append(f"\nPer receiver material ({sel} texels, luminance; RMS difference beyond "
                       "noise and the RMS noise of the difference, both relative to Luxel's mean):\n")
            out.append(md_table(["material", "texels", "E Luxel", "E Cycles", "Cycles / Luxel ± 1σ",
                                 "MSD / noise var.", "RMS diff. beyond noise", "RMS noise"],
                                [[g["material"], g["texels"], float(np.array(g["mean_E_luxel"]) @ LUM),
                                  float(np.array(g["mean_E_blender"]) @ LUM),
                                  f"{g['ratio_lum']:.4f} ± {g['ratio_lum_se']:.4f}",
                                  f"{g['mse_over_noise']:.2f}", f"{100 * g['diff_rms_rel']:.2f} %",
                                  f"{100 * g['noise_rms_rel']:.2f} %"] for g in rows[:24]]))
        for sel, c in a.get("crease", {}).items():
            out.append(f"\nNear creases ({sel} texels whose world point is within {fmt(c['distance'])} "
                       "(5 % of the scene's extent) of a turned surface rising above it: walls meeting "
                       "the ground, box sides) against the rest:\n")
            out.append(md_table(["texels", "count", "Cycles / Luxel ± 1σ", "MSD / noise var.",
                                 "RMS diff. beyond noise"],
                                [[part, c[part]["texels"], f"{c[part]['ratio_lum']:.4f} ± "
                                  f"{c[part]['ratio_lum_se']:.4f}", f"{c[part]['mse_over_noise']:.2f}",
                                  f"{100 * c[part]['diff_rms_rel']:.2f} %"] for part in ("near", "rest")]
                                + [["near / rest", "", f"{c['near_over_rest']['ratio']:.4f} ± "
                                    f"{c['near_over_rest']['se']:.4f}", "", ""]]))
        h = a.get("hires")
        if h:
            out.append(f"\nFlagged texels ({h['texels']}) against both renderers baked at "
                       f"{h['resolution']}² and box-filtered {h['factor']}x{h['factor']} down "
                       "(luminance; RMS relative to the mean of Luxel's filtered high-res map):\n")
            out.append(md_table(["map", "mean E", "RMS diff. vs Luxel high-res"],
                                [["Luxel " + str(st["resolution"]) + "²", h["mean"]["luxel"],
                                  f"{100 * h['rms_vs_luxel_hires']['luxel']:.1f} %"],
                                 ["Cycles " + str(st["resolution"]) + "²", h["mean"]["cycles"],
                                  f"{100 * h['rms_vs_luxel_hires']['cycles']:.1f} %"],
                                 [f"Luxel {h['resolution']}² filtered", h["mean"]["luxel_hires"], "0"],
                                 [f"Cycles {h['resolution']}² filtered", h["mean"]["cycles_hires"],
                                  f"{100 * h['rms_vs_luxel_hires']['cycles_hires']:.1f} %"]]))
        if not r["luxel"]:
            continue
        o = r["blender_overheads"]
        out.append(f"\nCycles costs outside the 'bake' column: Blender start {fmt(o['startup_s'])} s, "
                   f"glTF import {fmt(o['import_s'])} s, material and bake setup "
                   f"{fmt(o['setup_s'])} s, a first 1-spp warm-up bake {fmt(o['warmup_s'])} s "
                   "(each later bake call repeats Cycles' scene sync and BVH build: it is in "
                   "'bake s').\n")
        for label, rows in (("Luxel default spp", r["luxel"]), ("Luxel raw spp", r.get("luxel_raw"))):
            if not rows:
                continue
            out.append(md_table([label, "map", "trace s", "denoise s", "engine s", "process wall s",
                                 "Mpaths/s", "RMSE", "relMSE", "RMSE matched", "relMSE matched"],
                                [[x["spp"], x.get("denoise_method", "off"), x["trace_s"], x.get("denoise_s", 0.0),
                                  x.get("engine_s", x["trace_s"]), x["wall_s"], x["paths"] / x["trace_s"] / 1e6,
                                  x["interior"]["rmse"], x["interior"]["relmse"], x["matched"]["rmse"],
                                  x["matched"]["relmse"]] for x in rows]))
            out.append("")
        out.append(md_table(["Cycles spp (seed)", "bake s", "+ start, import s", "Msamples/s", "RMSE",
                             "relMSE", "relMSE matched", "relMSE vs own"],
                            [[f"{x['spp']} ({x['seed']})", x["bake_s"], x["cold_s"],
                              x["texels"] * x["spp"] / x["bake_s"] / 1e6, x["interior"]["rmse"],
                              x["interior"]["relmse"], x["matched"]["relmse"],
                              x["own"]["relmse"] if "own" in x else "-"]
                             for x in r["blender"]]))
        out.append("")
        if r.get("blender_oidn"):
            out.append(md_table(["Cycles + OIDN spp (seed)", "bake s", "denoise s", "bake + denoise s",
                                 "RMSE", "relMSE", "RMSE matched", "relMSE matched"],
                                [[f"{x['spp']} ({x['seed']})", x["bake_s"] - x["denoise_s"], x["denoise_s"],
                                  x["bake_s"], x["interior"]["rmse"], x["interior"]["relmse"],
                                  x["matched"]["rmse"], x["matched"]["relmse"]] for x in r["blender_oidn"]]))
            out.append("")
        sp = r["speed"]
        rows = []
        for key, label in (
                ("engine_matched_relmse", "**relMSE, matched texels, engine time** (Luxel default: trace + denoise vs Cycles bake call)"),
                ("raw_engine_matched_relmse", "relMSE, matched, raw vs raw (Luxel --denoise off trace vs Cycles bake call)"),
                ("oidn_engine_matched_relmse", "relMSE, matched, Luxel default vs Cycles + OIDN (bake + denoise)"),
                ("engine_matched_rmse", "RMSE, matched texels, engine time"),
                ("engine_interior_relmse", "relMSE, all interior texels, engine time"),
                ("end_to_end_matched_relmse", "relMSE, matched, end to end (Luxel process vs Blender start + import + bake)"),
                ("own_relmse", "relMSE vs each renderer's own converged map, engine time")):
            s = sp.get(key)
            if s is None:
                continue
            if not s["levels"]:
                rows.append([label, "-", "-", s.get("note", "")])
                continue
            rs = [lv["ratio"] for lv in s["levels"]]
            rows.append([label, f"{fmt(s['levels'][0]['error'])} .. {fmt(s['levels'][-1]['error'])}",
                         f"{min(rs):.2f} .. {max(rs):.2f}", f"{s['geomean_ratio']:.2f}"])
        out.append(md_table(["time to equal error: Cycles time / Luxel time (> 1: Luxel faster)",
                             "error levels", "ratio range", "geo. mean"], rows))
        spl = sp.get("split")
        if spl and "throughput_ratio" in spl:
            out.append(f"\nSplit (matched texels, rungs Luxel {spl['luxel']['rungs']}, Cycles "
                       f"{spl['cycles']['rungs']}): samples/s Luxel {fmt(spl['luxel']['samples_per_s'] / 1e6)} M, "
                       f"Cycles {fmt(spl['cycles']['samples_per_s'] / 1e6)} M (ratio "
                       f"{spl['throughput_ratio']:.2f}); relMSE x spp Luxel "
                       f"{fmt(spl['luxel']['relmse_x_spp'])}, Cycles {fmt(spl['cycles']['relmse_x_spp'])} "
                       f"(Cycles / Luxel {spl['error_per_sample_ratio']:.2f}); texels baked Luxel "
                       f"{fmt(spl['luxel']['texels'])}, Cycles {fmt(spl['cycles']['texels'])} (Cycles / "
                       f"Luxel {spl['texel_ratio']:.2f}); product "
                       f"{spl['throughput_ratio'] * spl['error_per_sample_ratio'] * spl['texel_ratio']:.2f}.\n")
        s = sp["engine_matched_relmse"]
        if s["levels"]:
            out.append("")
            out.append(md_table(["relMSE (matched)", "Luxel engine s", "Cycles bake s", "Cycles / Luxel"],
                                [[lv["error"], lv["luxel_s"], lv["blender_s"], f"{lv['ratio']:.2f}"]
                                 for lv in s["levels"]]))
    return "\n".join(out)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    root = sys.argv[1]
    scenes = [d for d in os.listdir(root) if os.path.isfile(os.path.join(root, d, "settings.json"))]
    order = ["sky_plane", "lights_plane", "cornell_box", "sky_courtyard", "lights_courtyard"]
    scenes.sort(key=lambda s: (order.index(s) if s in order else len(order), s))
    res = []
    for s in scenes:
        sdir = os.path.join(root, s)
        peers = peer_dirs(sdir)
        for version, d in peers:
            res.append(analyse(sdir, version, d, f"_cycles-{version}" if len(peers) > 1 else ""))
    with open(os.path.join(root, "summary.json"), "w") as f:
        json.dump(res, f, indent=1)
    print(report(res))


if __name__ == "__main__":
    main()
