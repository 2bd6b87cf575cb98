"""Scaling model of a sharded bake (coordinator + W workers), on paper.

A bake of T covered texels at S samples per texel traces P = S * T paths.
The coordinator splits it by sample index into W shards, one per worker;
every shard covers every texel, so every worker sends back a whole set of
accumulators. Time of the sharded bake:

    t(W) = setup                          scene import, BVH, atlas on each worker (in parallel)
         + W * scene_bytes / link         scene upload, coordinator -> each worker
         + max_i paths_i / rate_i         the slowest shard's tracing
         + W * T * state_bytes / link     accumulator download, each shard -> coordinator
         + W * T / merge_rate             exact merge (parallel Welford, Chan et al.)
         + finish                         dilation, EXR/PNG writing, manifest

state_bytes per covered texel is the BakeCheckpoint layout
(server/engine/shards/checkpoint.h): mean float4 + m2 float4 + weight
float2 + spp uint32 = 44 B, plus (1 + lobes) float4 per directional encoding
(bake/encodings.cpp: EncodingPlan::stride). Upload and download both go
through the coordinator's one network link ("link", Gbit/s), so they are
serial in W: this term and the merge grow with W while tracing shrinks as
1/W, and t(W) has a minimum at W* = sqrt(trace_1 / (per-shard overhead)).
The single-machine baseline is one luxeld without sharding: setup + P/rate
+ finish (no upload through the coordinator, no download, no merge).

Defaults are measured figures, each named below; the merge rate is the
coordinator's own (read back and fold, bench_shard_merge); --measure-merge N
measures the older numpy stand-in instead.

usage: shard_model.py [--link-gbit 1,10] [--paths-per-s R] [--topology star|tree] [--no-overlap] ... [--check]
"""
import argparse
import math
import sys
import time

BASE_BYTES = 16 + 16 + 8 + 4  # mean float4, m2 float4, weight float2, spp uint32
# Lobes per encoding (bake/encodings.cpp: stride += 1 + count).
LOBES = {"irradiance": None, "sh1": 4, "sh2": 9, "sg9": 9, "sg12": 12, "ad": 12}
WORKERS = (1, 2, 4, 8, 16, 32, 64, 100)


def state_bytes(encodings):
    """Accumulator bytes per covered texel for the given encodings."""
    extra = 0
    for e in encodings:
        if e not in LOBES:
            raise ValueError(f"unknown encoding {e!r} (known: {', '.join(LOBES)})")
        if LOBES[e] is not None:
            extra += 16 * (1 + LOBES[e])
    return BASE_BYTES + extra


def shard_paths(paths, rates, split):
    """Paths per shard: equal sample-index ranges, or in proportion to rate."""
    w = len(rates)
    if split == "equal":
        weights = [1.0] * w
    else:
        weights = rates
    total = sum(weights)
    return [paths * x / total for x in weights]


def sharded(p, w, link_bytes_per_s):
    """Time terms (seconds) of one bake over w workers."""
    paths = p.texels * p.samples
    rates = [p.paths_per_s] * (w - min(w, p.gpu_workers)) + \
            [p.paths_per_s * p.gpu_speedup] * min(w, p.gpu_workers)
    trace = max(n / r for n, r in zip(shard_paths(paths, rates, p.split), rates))
    upload = w * p.scene_mb * 1e6 / link_bytes_per_s
    shard_bytes = p.texels * state_bytes(p.encodings)
    if p.topology == "star":
        # Every shard through the coordinator's link, merged there one by one.
        download = w * shard_bytes / link_bytes_per_s
        merge = w * p.texels / p.merge_rate
    else:
        # Pairwise tree: ceil(log2 W) rounds, the pairs of a round on their
        # own links (a non-blocking switch), merging in parallel.
        rounds = math.ceil(math.log2(w)) if w > 1 else 1
        download = rounds * shard_bytes / link_bytes_per_s
        merge = rounds * p.texels / p.merge_rate
    if p.overlap:
        # Shard k merges while shard k+1 downloads: the slower stream plus
        # one step of the other.
        dl_merge = max(download, merge) + min(download, merge) / w
    else:
        dl_merge = download + merge
    total = p.setup_s + upload + trace + dl_merge + p.finish_s
    return {"trace": trace, "upload": upload, "download": download, "merge": merge,
            "dl_merge": dl_merge, "total": total,
            "overhead": (upload + dl_merge) / total}


def single(p):
    """One luxeld, no sharding."""
    return p.setup_s + p.texels * p.samples / p.paths_per_s + p.finish_s


def best_workers(p, link_bytes_per_s, limit=1000):
    """The W in 1..limit with the shortest t(W)."""
    return min(range(1, limit + 1), key=lambda w: sharded(p, w, link_bytes_per_s)["total"])


def best_workers_star(p, link_bytes_per_s):
    """Closed form for the star, identical workers, no overlap: d/dW of
    trace_1 / W + W * c is zero at W* = sqrt(trace_1 / c)."""
    trace_1 = p.texels * p.samples / p.paths_per_s
    c = p.scene_mb * 1e6 / link_bytes_per_s + \
        p.texels * state_bytes(p.encodings) / link_bytes_per_s + p.texels / p.merge_rate
    return math.sqrt(trace_1 / c)


def table(p, link_gbit, workers=WORKERS):
    link = link_gbit * 1e9 / 8
    base = single(p)
    rows = []
    for w in workers:
        r = sharded(p, w, link)
        rows.append((w, r, base / r["total"]))
    return base, rows


def print_tables(p):
    print(f"bake: {p.texels:,} covered texels x {p.samples} spp = "
          f"{p.texels * p.samples / 1e9:.2f} G paths; {state_bytes(p.encodings)} B/texel "
          f"({'+'.join(p.encodings)}), shard state {p.texels * state_bytes(p.encodings) / 1e6:.0f} MB; "
          f"{p.paths_per_s / 1e6:.2f} M paths/s per worker; merge {p.merge_rate / 1e6:.2f} M texels/s; "
          f"setup {p.setup_s} s, finish {p.finish_s} s; scene {p.scene_mb} MB; "
          f"download and merge {'overlapped' if p.overlap else 'serial'}, {p.topology}")
    for g in p.link_gbit:
        base, rows = table(p, g)
        print(f"\nlink {g:g} Gbit/s (single luxeld: {base:,.1f} s)")
        print("| W | time s | trace s | upload s | download s | merge s | speedup | efficiency | overhead |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for w, r, s in rows:
            # Efficiency against the pool's capacity in CPU-worker units.
            capacity = w - min(w, p.gpu_workers) + min(w, p.gpu_workers) * p.gpu_speedup
            print(f"| {w} | {r['total']:,.1f} | {r['trace']:,.1f} | {r['upload']:.1f} | "
                  f"{r['download']:.1f} | {r['merge']:.1f} | {s:.2f}x | {s / capacity:.0%} | "
                  f"{r['overhead']:.1%} |")
        wstar = best_workers(p, g * 1e9 / 8)
        why = "as W" if p.topology == "star" else "as log2 W"
        print(f"fastest at W* = {wstar} workers (transfer + merge grow {why}, "
              "tracing falls as 1/W)")
        r16 = sharded(p, 16, g * 1e9 / 8)
        verdict = "met" if r16["overhead"] <= 0.05 else "NOT met"
        print(f"goal merge+transfer <= 5 % at 16 workers: {r16['overhead']:.1%} ({verdict})")


def measure_merge(n, repeats=3):
    """Texels per second of a numpy weighted Chan-Welford merge of two
    accumulator sets of n texels (the layout of BakeCheckpoint: mean and m2
    float4, weight float2 = (sum w, sum w^2), spp uint32). A stand-in: the
    coordinator merges in C++."""
    import numpy as np
    rng = np.random.default_rng(1)
    a = (rng.random((n, 4), np.float32), rng.random((n, 4), np.float32),
         rng.random((n, 2), np.float32) + 1, rng.integers(1, 100, n, dtype=np.uint32))
    b = (rng.random((n, 4), np.float32), rng.random((n, 4), np.float32),
         rng.random((n, 2), np.float32) + 1, rng.integers(1, 100, n, dtype=np.uint32))
    best = math.inf
    for _ in range(repeats):
        mean, m2, weight, spp = (x.copy() for x in a)
        t0 = time.perf_counter()
        # In place into the running set, as a coordinator folds shards in.
        wa = weight[:, :1]
        wb = b[2][:, :1]
        w = wa + wb
        delta = b[0] - mean
        m2 += b[1]
        m2 += delta * delta * (wa * wb / w)
        mean += delta * (wb / w)
        weight += b[2]
        spp += b[3]
        best = min(best, time.perf_counter() - t0)
    return n / best


def check():
    """The arithmetic against a case worked by hand."""
    p = argparse.Namespace(texels=1000, samples=100, paths_per_s=1000.0, gpu_workers=0, topology="star",
                           gpu_speedup=1.0, split="equal", scene_mb=0.001, encodings=["irradiance"],
                           merge_rate=1e5, setup_s=2.0, finish_s=3.0, overlap=False)
    link = 1e6 / 8  # 1 Mbit/s = 125,000 B/s
    r = sharded(p, 4, link)
    # trace 100,000 paths / 4 / 1000 = 25 s; upload 4 x 1000 B / 125,000 = 0.032 s;
    # download 4 x 1000 x 44 B / 125,000 = 1.408 s; merge 4000 / 1e5 = 0.04 s;
    # total 2 + 0.032 + 25 + 1.408 + 0.04 + 3 = 31.48 s; single 2 + 100 + 3 = 105 s.
    expect = {"trace": 25.0, "upload": 0.032, "download": 1.408, "merge": 0.04, "total": 31.48}
    for k, v in expect.items():
        assert math.isclose(r[k], v, rel_tol=1e-9), (k, r[k], v)
    assert math.isclose(single(p), 105.0)
    assert math.isclose(r["overhead"], (0.032 + 1.408 + 0.04) / 31.48)
    assert math.isclose(105.0 / r["total"], 3.3354510800508257)
    # W* = sqrt(100 / (0.008 + 0.352 + 0.01)) = sqrt(270.27) = 16.44; the
    # integer search lands next to it.
    assert math.isclose(best_workers_star(p, link), math.sqrt(100 / 0.37))
    assert best_workers(p, link) in (16, 17)
    # Tree: 4 workers, 2 rounds: download 2 x 0.352 = 0.704 s, merge 2 x 0.01.
    p.topology = "tree"
    r = sharded(p, 4, link)
    assert math.isclose(r["download"], 0.704) and math.isclose(r["merge"], 0.02)
    assert math.isclose(r["total"], 2 + 0.032 + 25 + 0.704 + 0.02 + 3)
    p.topology = "star"
    # Encodings: SG12 adds 13 float4 = 208 B (docs/performance.md: "SG12: 208").
    assert state_bytes(["irradiance"]) == 44 and state_bytes(["irradiance", "sg12"]) == 252
    # A GPU worker 3x as fast: equal shards wait for the CPU ones, rate-sized
    # shards do not. 2 CPU + 2 GPU, 100,000 paths: equal 25,000 / 1000 = 25 s;
    # proportional: 100,000 / (2 x 1000 + 2 x 3000) = 12.5 s.
    p.gpu_workers, p.gpu_speedup = 2, 3.0
    assert math.isclose(sharded(p, 4, link)["trace"], 25.0)
    p.split = "rate"
    assert math.isclose(sharded(p, 4, link)["trace"], 12.5)
    # Overlapped: max(1.408, 0.04) + 0.04 / 4.
    p.overlap = True
    assert math.isclose(sharded(p, 4, link)["dl_merge"], 1.408 + 0.01)
    # An injected error must be caught: 45 B per texel moves the download.
    assert not math.isclose(4 * 1000 * 45 / link, expect["download"], rel_tol=1e-9)
    print("shard_model: hand-computed case agrees")


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    # 4096² Cornell box: 10,786,735 covered texels (docs/performance.md,
    # "Device memory at large lightmaps").
    a.add_argument("--texels", type=int, default=10_786_735, help="covered texels")
    a.add_argument("--samples", type=int, default=256, help="samples per texel (luxel's default)")
    # Sponza 1024², 1 bounce, Embree, 2-core Xeon: 1.02 M paths/s
    # (docs/performance.md, "Ray-query backends").
    a.add_argument("--paths-per-s", type=float, default=1.02e6, help="per worker")
    a.add_argument("--gpu-workers", type=int, default=0, help="of the W workers, this many on GPUs")
    a.add_argument("--gpu-speedup", type=float, default=1.0, help="GPU worker rate / CPU worker rate")
    a.add_argument("--split", choices=("equal", "rate"), default="equal",
                   help="shards of equal samples, or sized by worker rate")
    a.add_argument("--link-gbit", default="1,10", help="coordinator link(s), Gbit/s")
    a.add_argument("--scene-mb", type=float, default=35.1, help="scene upload (sponza.glb: 35.1 MB)")
    a.add_argument("--encodings", default="irradiance", help=f"comma list of {', '.join(LOBES)}")
    a.add_argument("--merge-rate", type=float, default=None,
                   help="merged texels/s at the coordinator, reading each shard back "
                        "included (default: bench_shard_merge's figure in docs/performance.md; "
                        "--measure-merge for the numpy stand-in)")
    a.add_argument("--setup-s", type=float, default=5.7,
                   help="per-worker setup (bench_bake --memory, 4096² Cornell box: 5.7 s)")
    a.add_argument("--finish-s", type=float, default=None, help="dilation + writing at 4096²")
    a.add_argument("--no-overlap", dest="overlap", action="store_false",
                   help="merge after every shard has downloaded (the coordinator folds each "
                        "shard as it arrives: overlap is the default)")
    a.add_argument("--topology", choices=("star", "tree"), default="star",
                   help="every shard to the coordinator (star), or pairwise merges among the "
                        "workers first (tree)")
    a.add_argument("--measure-merge", type=int, metavar="N", default=0,
                   help="measure the numpy merge on N texels and use it")
    a.add_argument("--check", action="store_true",
                   help="check the arithmetic against a hand-computed case first")
    p = a.parse_args()
    if p.check:
        check()
    p.encodings = p.encodings.split(",")
    p.link_gbit = [float(x) for x in p.link_gbit.split(",")]
    if p.measure_merge:
        p.merge_rate = measure_merge(p.measure_merge)
        print(f"numpy merge of {p.measure_merge:,} texels: {p.merge_rate / 1e6:.1f} M texels/s")
    if p.merge_rate is None:
        p.merge_rate = MERGE_RATE
    if p.finish_s is None:
        p.finish_s = FINISH_S
    print_tables(p)
    return 0


# Measured defaults (docs/performance.md, "Sharded bakes: a scaling model").
# The coordinator's read + fold of shard states, C++ (bench_shard_merge,
# 4 x 10.8 M texels, 2-core AMD EPYC): 4.76 M texels/s.
MERGE_RATE = 4.76e6
FINISH_S = 10.0

if __name__ == "__main__":
    sys.exit(main())
