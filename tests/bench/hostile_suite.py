#!/usr/bin/python3
"""A hostile client against one luxeld: memory bombs, CPU bombs, settings
that submit could have refused, and cancels in every phase. Per class it
reports the cases, how many the daemon held, its RSS, threads and open fds
before and after, and the largest RSS any single request caused
(docs/operations.md, "Hostile clients"):

    PYTHONPATH=client/python:BUILD/python /usr/bin/python3 tests/bench/hostile_suite.py \\
        --luxeld BUILD/server/service/luxeld [--classes memory,cpu,late,cancel] \\
        [--out /tmp/hostile] [-- extra luxeld flags, e.g. --import-memory-budget 1GiB]

A case is held when the daemon answers as a careful server would: a bomb is
refused naming the accessor, extension or image (or imported within the
budget), a CPU bomb ends within the import deadline, a setting submit could
have judged is refused at submit naming `settings.<field>` (or the bake it
accepted succeeds), and a cancel reaches CANCELLED within 0.5 s of the call,
whose own return is immediate. After every case the daemon must still answer.
The RSS figures are sampled every 5 ms from /proc/PID/status (VmRSS).
"""

import argparse
import hashlib
import json
import os
import pathlib
import struct
import sys
import tempfile
import threading
import time
import zlib

_REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(_REPO / "client/python"))
sys.path.insert(0, str(_REPO / "tests/python"))

from luxel_client import Client, LuxelError, luxel_pb2, state_name  # noqa: E402
from luxeld_process import Luxeld  # noqa: E402

CORNELL = _REPO / "scenes/cornell_box.gltf"
MIB = 1 << 20
TERMINAL = ("SUCCEEDED", "FAILED", "CANCELLED")


# ---------------------------------------------------------------- the daemon's vitals

class Vitals:
    """RSS, threads and fds of one process; a sampler thread keeps the peak
    RSS since the last reset()."""

    def __init__(self, pid, kill_above):
        self.pid = pid
        self.peak = 0
        self.base = 0
        # A daemon that is not held is killed before it takes the machine.
        self.kill_above = kill_above
        self.killed = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()

    def rss(self):
        with open(f"/proc/{self.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
        return 0

    def snapshot(self):
        if not os.path.exists(f"/proc/{self.pid}/status"):
            return dict(rss_mib="killed", threads="-", fds="-")
        return dict(rss_mib=round(self.rss() / MIB, 1),
                    threads=len(os.listdir(f"/proc/{self.pid}/task")),
                    fds=len(os.listdir(f"/proc/{self.pid}/fd")))

    def _sample(self):
        while not self._stop.is_set():
            try:
                self.peak = max(self.peak, self.rss())
                if self.peak > self.kill_above and not self.killed:
                    self.killed = True
                    os.kill(self.pid, 9)
                    print(f"hostile_suite: killed the daemon at {self.peak / MIB:.0f} MiB",
                          file=sys.stderr, flush=True)
            except OSError:
                return
            time.sleep(0.005)

    def reset(self):
        self.base = self.peak = self.rss()

    def growth(self):
        return self.peak - self.base

    def close(self):
        self._stop.set()


# ---------------------------------------------------------------- hostile files

def gltf(doc, buffers=None, images=None):
    """A glTF dict with the asset header; returns (json text, {uri: bytes})."""
    doc = dict({"asset": {"version": "2.0"}, "scene": 0}, **doc)
    files = {}
    for uri, data in (buffers or {}).items():
        files[uri] = data
    for uri, data in (images or {}).items():
        files[uri] = data
    return json.dumps(doc), files


def triangle_doc(extra_accessor=None, primitive=None, node=None, stride=None, scale=1.0):
    """One triangle in a buffer; the keys replace parts of it."""
    positions = struct.pack("<9f", *(v * scale for v in (0, 0, 0, 1, 0, 0, 0, 1, 0)))
    view = {"buffer": 0, "byteOffset": 0, "byteLength": len(positions)}
    if stride is not None:
        view["byteStride"] = stride
    acc = {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
           "min": [0, 0, 0], "max": [scale, scale, 0]}
    prim = dict({"attributes": {"POSITION": 0}}, **(primitive or {}))
    doc = {"buffers": [{"uri": "tri.bin", "byteLength": len(positions)}],
           "bufferViews": [view], "accessors": [acc] + ([extra_accessor] if extra_accessor else []),
           "meshes": [{"primitives": [prim]}],
           "nodes": [dict({"mesh": 0}, **(node or {}))], "scenes": [{"nodes": [0]}]}
    return doc, {"tri.bin": positions}


def png(width, height, zero_rows=True):
    """An all-zero RGB PNG of width x height (rows compress to almost
    nothing), or only its header when zero_rows is False (a lying header)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(
            ">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    if zero_rows:
        c = zlib.compressobj(9)
        row = bytes(1 + 3 * width)
        idat = b"".join(c.compress(row) for _ in range(height)) + c.flush()
    else:
        idat = zlib.compress(bytes(1 + 3 * 16))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def textured_doc(n_images, width, height, header_only=False):
    doc, files = triangle_doc()
    doc["images"] = [{"uri": f"zero{i}.png"} for i in range(n_images)]
    doc["textures"] = [{"source": i} for i in range(n_images)]
    doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": i}}}
                        for i in range(n_images)]
    doc["meshes"][0]["primitives"] = [dict(doc["meshes"][0]["primitives"][0], material=i)
                                      for i in range(n_images)]
    image = png(width, height, zero_rows=not header_only)
    for i in range(n_images):
        files[f"zero{i}.png"] = image
    return doc, files


def node_graph(n, chain):
    doc, files = triangle_doc()
    nodes = [{"mesh": 0}]
    for i in range(1, n):
        node = {"translation": [0.001, 0, 0]}
        if chain and i + 1 < n:
            node["children"] = [i + 1]
        nodes.append(node)
    nodes[0]["children"] = [1] if chain else []
    doc["nodes"] = nodes
    doc["scenes"] = [{"nodes": [0] if chain else list(range(n))}]
    return doc, files


def write_scene(root, name, doc, files):
    folder = pathlib.Path(root) / name
    folder.mkdir(parents=True, exist_ok=True)
    text, extra = gltf(doc)
    for uri, data in files.items():
        (folder / uri).write_bytes(data)
    path = folder / "scene.gltf"
    path.write_text(text)
    return path


# ---------------------------------------------------------------- the suite

class Suite:
    def __init__(self, daemon, vitals, out):
        self.daemon = daemon
        self.vitals = vitals
        self.out = pathlib.Path(out)
        self.rows = []

    def client(self):
        return Client(self.daemon.address, timeout=600)

    def alive(self):
        if self.daemon.process.poll() is not None:
            return False
        try:
            with self.client() as c:
                c.server_status()
            return True
        except LuxelError:
            return False

    def case(self, klass, name, run):
        self.vitals.reset()
        start = time.monotonic()
        try:
            held, detail = run()
        except LuxelError as e:
            held, detail = False, f"unexpected {e.code}: {e.message}"
        except Exception as e:  # noqa: BLE001 - a bench reports every failure
            held, detail = False, f"{type(e).__name__}: {e}"
        seconds = time.monotonic() - start
        alive = self.alive()
        row = dict(klass=klass, case=name, held=bool(held and alive), seconds=round(seconds, 3),
                   peak_rss_mib=round(self.vitals.peak / MIB, 1),
                   growth_mib=round(self.vitals.growth() / MIB, 1), detail=detail[:300],
                   daemon_alive=alive)
        self.rows.append(row)
        print(json.dumps(row), flush=True)

    # ---- helpers for the cases

    def upload(self, path):
        with self.client() as c:
            return c.upload_scene(path)

    def refused(self, path, codes, words):
        """Held when the upload is refused with one of `codes` and a message
        naming one of `words`; accepted uploads are not held."""
        try:
            info = self.upload(path)
            return False, f"accepted as {info.scene_id}"
        except LuxelError as e:
            ok = e.code in codes and any(w in e.message for w in words)
            return ok, f"{e.code}: {e.message}"

    def within_budget(self, path, budget_bytes, words):
        """A bomb that may be imported when it fits: held when refused
        RESOURCE_EXHAUSTED naming it, or imported with the daemon's peak
        under its import budget."""
        try:
            info = self.upload(path)
            grew = self.vitals.growth()
            return grew < budget_bytes, (f"accepted ({info.statistics.triangles} triangles), "
                                         f"grew {grew / MIB:.0f} MiB against "
                                         f"{budget_bytes / MIB:.0f}")
        except LuxelError as e:
            return (e.code == "RESOURCE_EXHAUSTED" and any(w in e.message for w in words),
                    f"{e.code}: {e.message}")

    def submit_refused(self, scene_id, field, **settings):
        """Held when submit refuses naming settings.<field>, or when what it
        accepted then succeeds (tiny bakes)."""
        base = dict(samples_per_texel=1, max_bounces=1)
        with self.client() as c:
            try:
                info = c.submit_bake(scene_id, **dict(base, **settings))
            except LuxelError as e:
                return (e.code in ("INVALID_ARGUMENT", "RESOURCE_EXHAUSTED", "NOT_FOUND",
                                   "FAILED_PRECONDITION") and f"settings.{field}" in e.message,
                        f"{e.code}: {e.message}")
            info = self.wait(c, info.bake_id, 300)
            state = state_name(info.state)
            if state != "SUCCEEDED":
                c.cancel_bake(info.bake_id)
            return state == "SUCCEEDED", f"accepted, then {state}: {info.error_message}"

    @staticmethod
    def wait(c, bake_id, timeout):
        deadline = time.monotonic() + timeout
        info = c.get_bake(bake_id)
        while state_name(info.state) not in TERMINAL and time.monotonic() < deadline:
            time.sleep(0.05)
            info = c.get_bake(bake_id)
        return info

    # ---- the classes

    def memory(self, import_budget, host_budget):
        root = self.out / "memory"
        # POSITION without a bufferView: 3 * 2^24 declared zero vertices.
        doc, files = triangle_doc()
        doc["accessors"][0] = {"componentType": 5126, "count": 3 << 24, "type": "VEC3",
                               "min": [0, 0, 0], "max": [0, 0, 0]}
        path = write_scene(root, "zero_accessor", doc, files)
        self.case("memory", "accessor without bufferView, 3*2^24 vertices",
                  lambda: self.within_budget(path, import_budget, ("accessor",)))
        # EXT_mesh_gpu_instancing: 10^6 zero translations of a 32-triangle mesh.
        doc, files = triangle_doc()
        tris = struct.pack("<" + "f" * 9 * 32, *([0, 0, 0, 1, 0, 0, 0, 1, 0] * 32))
        files["tri.bin"] = tris
        doc["buffers"][0]["byteLength"] = len(tris)
        doc["bufferViews"][0]["byteLength"] = len(tris)
        doc["accessors"][0]["count"] = 96
        doc["accessors"].append({"componentType": 5126, "count": 10 ** 6, "type": "VEC3"})
        doc["nodes"][0]["extensions"] = {"EXT_mesh_gpu_instancing": {"attributes": {
            "TRANSLATION": 1}}}
        doc["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
        path = write_scene(root, "instancing", doc, files)
        self.case("memory", "EXT_mesh_gpu_instancing, 10^6 instances of 32 triangles",
                  lambda: self.within_budget(path, import_budget,
                                             ("EXT_mesh_gpu_instancing", "instanc")))
        # Four all-zero 16384 x 4000 PNGs (one upload), then four such uploads at once.
        path = write_scene(root, "zero_pngs", *textured_doc(4, 16384, 4000))
        self.case("memory", "4 all-zero 16384x4000 PNGs in one upload",
                  lambda: self.within_budget(path, import_budget, ("image", "png", "zero")))

        def concurrent():
            paths = []
            for i in range(4):
                d, f = textured_doc(4, 16384, 4000 + i)  # distinct files: no dedup
                paths.append(write_scene(root, f"zero_pngs_{i}", d, f))
            results = [None] * 4

            def one(i):
                try:
                    results[i] = self.upload(paths[i]).scene_id
                except LuxelError as e:
                    results[i] = f"{e.code}: {e.message}"
            threads = [threading.Thread(target=one, args=(i,)) for i in range(4)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            refused_clearly = all(r and (not r.startswith(("INVALID", "INTERNAL", "UNKNOWN")))
                                  for r in results)
            return (refused_clearly and self.vitals.growth() < import_budget,
                    f"grew {self.vitals.growth() / MIB:.0f} MiB; " + " | ".join(results))
        self.case("memory", "4 such uploads at once (one shared budget)", concurrent)
        path = write_scene(root, "png_header", *textured_doc(1, 65535, 65535, header_only=True))
        self.case("memory", "PNG header claiming 65535x65535",
                  lambda: self.refused(path, ("INVALID_ARGUMENT", "RESOURCE_EXHAUSTED"),
                                       ("too large", "exceeds the limit")))
        # A bake whose host state (8 directional encodings at 4096^2) is far
        # past any reasonable host budget: refused at submit, or kept under it.
        scene = self.upload(CORNELL)

        def big_bake():
            with self.client() as c:
                try:
                    info = c.submit_bake(scene.scene_id, resolution=4096, samples_per_texel=1,
                                         encodings="sh1,sh2,sg6,sg9,sg12,sg6-hemi,sg9-hemi,sg12-hemi")
                except LuxelError as e:
                    return (e.code == "RESOURCE_EXHAUSTED" and "settings." in e.message,
                            f"{e.code}: {e.message}")
                # Accepted: it must stay under the host budget while it runs.
                deadline = time.monotonic() + 120
                while time.monotonic() < deadline and self.vitals.growth() < host_budget:
                    if state_name(c.get_bake(info.bake_id).state) in TERMINAL:
                        break
                    time.sleep(0.2)
                c.cancel_bake(info.bake_id)
                self.wait(c, info.bake_id, 60)
                return self.vitals.growth() < host_budget, (
                    f"accepted; grew {self.vitals.growth() / MIB:.0f} MiB against "
                    f"{host_budget / MIB:.0f}")
        self.case("memory", "4096^2 bake with 8 directional encodings", big_bake)

    def cpu(self, timeout_s):
        root = self.out / "cpu"
        for n, chain in ((100_000, False), (100_000, True)):
            path = write_scene(root, f"nodes_{n}_{int(chain)}", *node_graph(n, chain))

            def run(path=path):
                start = time.monotonic()
                try:
                    info = self.upload(path)
                    took = time.monotonic() - start
                    return took < timeout_s, f"imported in {took:.2f} s ({info.scene_id[:12]})"
                except LuxelError as e:
                    took = time.monotonic() - start
                    return (e.code == "DEADLINE_EXCEEDED" and took < timeout_s + 5,
                            f"{e.code} after {took:.2f} s: {e.message}")
            self.case("cpu", f"{n} nodes, {'one chain' if chain else 'flat'}", run)
        folder = root / "nesting"
        folder.mkdir(parents=True, exist_ok=True)
        deep = folder / "scene.gltf"
        deep.write_text('{"asset":{"version":"2.0"},"extras":' + "[" * 100_000 + "]" * 100_000 + "}")

        def nested():
            # Sent as raw bytes: the Python client would parse the JSON
            # itself (to find resources) and hit its own recursion limit.
            data = deep.read_bytes()
            header = luxel_pb2.SceneUploadHeader(
                name="scene.gltf", format=luxel_pb2.SCENE_FORMAT_GLTF, total_size=len(data),
                sha256=hashlib.sha256(data).hexdigest())
            try:
                with self.client() as c:
                    c._upload(header, [data[i:i + MIB] for i in range(0, len(data), MIB)])
                return False, "accepted"
            except LuxelError as e:
                return (e.code == "INVALID_ARGUMENT" and
                        any(w in e.message for w in ("nest", "deep", "depth")),
                        f"{e.code}: {e.message}")
        self.case("cpu", "JSON nested 100,000 levels", nested)

    def late(self):
        root = self.out / "late"
        scene = self.upload(CORNELL).scene_id
        settings_cases = [
            ("probes grid:0.001", "probes", dict(probes="grid:0.001")),
            ("probes grid:0.01", "probes", dict(probes="grid:0.01")),
            ("probes adaptive:1e-6", "probes", dict(probes="adaptive:1e-6")),
            ("probes grid:1e-9", "probes", dict(probes="grid:1e-9")),
            ("probes grid:1e-30", "probes", dict(probes="grid:1e-30")),
            ("probes grid:1 in a 1e30 box", "probes",
             dict(probes="grid:1:box=-1e30,-1e30,-1e30,1e30,1e30,1e30")),
            ("probes file: a position of 1e39", "probe",
             dict(probes="file:p.json", probe_positions="[[1e39, 0, 0]]")),
            ("probes file: 2^20+1 positions", "probe",
             dict(probes="file:p.json", probe_positions=json.dumps([[0, 0, 0]] * ((1 << 20) + 1)))),
            ("probes nodes without probe nodes", "probes", dict(probes="nodes")),
            ("sun.direction (1e-45,0,0)", "sun",
             dict(sun={"direction": (1e-45, 0, 0), "illuminance": 1.0})),
            ("uv=generate at resolution 16", "", dict(uv="generate", resolution=16)),
        ]
        for name, field, settings in settings_cases:
            self.case("late", name, lambda f=field, s=settings: self.submit_refused(scene, f, **s))

        def reference_of_other_size():
            with self.client() as c:
                ref = c.submit_bake(scene, resolution=32, samples_per_texel=1, max_bounces=1)
                self.wait(c, ref.bake_id, 300)
            return self.submit_refused(scene, "reference_bake_id", resolution=48,
                                       reference_bake_id=ref.bake_id)
        self.case("late", "reference_bake_id of another resolution", reference_of_other_size)
        uploads = []
        doc, files = triangle_doc()
        doc["meshes"][0]["primitives"][0]["mode"] = 0  # points only: 0 triangles
        uploads.append(("0 triangles", write_scene(root, "no_triangles", doc, files),
                        ("triangle",)))
        uploads.append(("coordinates at 1e308 scale",
                        write_scene(root, "huge", *triangle_doc(node={"scale": [1e308] * 3})),
                        ("scale", "coordinate", "finite", "large")))
        uploads.append(("byteStride 0", write_scene(root, "stride0", *triangle_doc(stride=0)),
                        ("byteStride", "accessor", "bufferView")))
        uploads.append(("material -5",
                        write_scene(root, "material", *triangle_doc(primitive={"material": -5})),
                        ("material",)))
        for name, path, words in uploads:
            self.case("late", f"upload: {name}",
                      lambda p=path, w=words: self.refused(p, ("INVALID_ARGUMENT",), w))

    def cancel(self):
        scene = self.upload(CORNELL).scene_id
        heavy = dict(resolution=2048, samples_per_texel=4096, encodings="sh2,sg12")

        def cancel_after(delay, phase_check=None):
            with self.client() as c:
                info = c.submit_bake(scene, **(dict(heavy, samples_per_texel=8, denoise="atrous")
                                               if delay == "finishing" else heavy))
                if delay is None:
                    # Queued behind a running bake.
                    blocker = info
                    info = c.submit_bake(scene, **dict(heavy, resolution=64))
                    while state_name(c.get_bake(info.bake_id).state) != "QUEUED":
                        time.sleep(0.01)
                else:
                    blocker = None
                    while state_name(c.get_bake(info.bake_id).state) != "RUNNING":
                        time.sleep(0.005)
                    if delay == "tracing":
                        while c.get_bake(info.bake_id).progress.paths == 0:
                            time.sleep(0.01)
                    elif delay == "finishing":
                        # The last iteration done: read-back, denoise and
                        # outputs still to come.
                        while (c.get_bake(info.bake_id).progress.fraction < 1 and
                               state_name(c.get_bake(info.bake_id).state) not in TERMINAL):
                            time.sleep(0.002)
                    else:
                        time.sleep(delay)
                at = c.get_bake(info.bake_id)
                phase = f"{state_name(at.state)}, {at.progress.paths} paths:"
                t0 = time.monotonic()
                c.cancel_bake(info.bake_id)
                returned = time.monotonic() - t0
                while state_name(c.get_bake(info.bake_id).state) not in TERMINAL:
                    time.sleep(0.005)
                    if time.monotonic() - t0 > 120:
                        break
                ended = time.monotonic() - t0
                final = state_name(c.get_bake(info.bake_id).state)
                if blocker:
                    c.cancel_bake(blocker.bake_id)
                    self.wait(c, blocker.bake_id, 120)
                return (final == "CANCELLED" and ended < 0.5,
                        f"{phase} call returned in {returned:.3f} s, {final} after {ended:.3f} s")
        for label, delay in (("queued", None), ("0.3 s after RUNNING", 0.3),
                             ("1.5 s after RUNNING", 1.5), ("4.0 s after RUNNING", 4.0),
                             ("while tracing", "tracing"),
                             ("after the last iteration (8 spp, a-trous)", "finishing")):
            self.case("cancel", label, lambda d=delay: cancel_after(d))


def parse_bytes(text):
    units = {"": 1, "kib": 1 << 10, "mib": 1 << 20, "gib": 1 << 30}
    t = text.strip().lower()
    for u in ("kib", "mib", "gib"):
        if t.endswith(u):
            return int(float(t[:-3]) * units[u])
    return int(float(t))


def flag(extra, name, default):
    return extra[extra.index(name) + 1] if name in extra else default


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--luxeld", required=True)
    p.add_argument("--classes", default="memory,cpu,late,cancel")
    p.add_argument("--out", default=None)
    p.add_argument("--import-budget", default=None,
                   help="judge imports against this (default: the daemon's --import-memory-budget, "
                        "else 3GiB)")
    p.add_argument("--host-budget", default=None,
                   help="judge and stop a running bake at this growth (default: the daemon's "
                        "--host-memory-budget, else 12GiB)")
    p.add_argument("extra", nargs="*", help="flags passed to luxeld (after --)")
    args = p.parse_args(argv)
    out = args.out or tempfile.mkdtemp(prefix="luxel_hostile_")
    # The budgets the cases are judged against: the daemon's flags, else
    # what it reports as its defaults is not visible from outside, so the
    # suite states them (pass the flags to judge other values).
    import_budget = parse_bytes(args.import_budget or
                                flag(args.extra, "--import-memory-budget", "3GiB"))
    host_budget = parse_bytes(args.host_budget or flag(args.extra, "--host-memory-budget", "12GiB"))
    import_timeout = float(flag(args.extra, "--import-timeout", "300"))
    kill_above = max(2 * host_budget, 4 * import_budget)
    daemon = Luxeld(args.luxeld, extra_args=args.extra).start()
    vitals = Vitals(daemon.process.pid, kill_above)
    suite = Suite(daemon, vitals, out)
    summary = []
    try:
        for klass in args.classes.split(","):
            if daemon.process.poll() is not None:
                # The watchdog killed it: a fresh daemon for the next class.
                vitals.close()
                daemon.cleanup()
                daemon = Luxeld(args.luxeld, extra_args=args.extra).start()
                vitals = Vitals(daemon.process.pid, kill_above)
                suite.daemon, suite.vitals = daemon, vitals
            time.sleep(1)
            before = vitals.snapshot()
            first = len(suite.rows)
            if klass == "memory":
                suite.memory(import_budget, host_budget)
            elif klass == "cpu":
                suite.cpu(import_timeout)
            elif klass == "late":
                suite.late()
            elif klass == "cancel":
                suite.cancel()
            time.sleep(2)
            after = vitals.snapshot()
            rows = suite.rows[first:]
            summary.append(dict(klass=klass, cases=len(rows), held=sum(r["held"] for r in rows),
                                before=before, after=after,
                                largest_request_rss_mib=max((r["peak_rss_mib"] for r in rows),
                                                            default=0),
                                largest_request_growth_mib=max((r["growth_mib"] for r in rows),
                                                               default=0)))
    finally:
        vitals.close()
        daemon.cleanup()
    print("\n| class | cases | held | RSS before → after (MiB) | threads | fds | "
          "largest RSS during one request (MiB) | its growth (MiB) |")
    print("|---|---:|---:|---|---|---|---:|---:|")
    for s in summary:
        b, a = s["before"], s["after"]
        print(f"| {s['klass']} | {s['cases']} | {s['held']} | {b['rss_mib']} → {a['rss_mib']} | "
              f"{b['threads']} → {a['threads']} | {b['fds']} → {a['fds']} | "
              f"{s['largest_request_rss_mib']} | {s['largest_request_growth_mib']} |")
    print("\nNot held:")
    for r in suite.rows:
        if not r["held"]:
            print(f"- {r['klass']}: {r['case']}: {r['detail']}")
    pathlib.Path(out).mkdir(parents=True, exist_ok=True)
    (pathlib.Path(out) / "hostile.json").write_text(json.dumps(
        dict(rows=suite.rows, summary=summary), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
