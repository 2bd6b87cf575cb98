#!/usr/bin/python3
"""End-to-end test of the `luxel` CLI against a real luxeld on loopback.

Starts luxeld on a free port with a fresh data folder, then drives every
remote command of the CLI and checks exit codes, JSON output and the files
written (artifacts verified against sha256 computed here, independently of
the CLI). Also: a missing bearer token gives UNAUTHENTICATED (exit 1), and a
TLS daemon is reachable with --tls-ca. Stdlib only (Debian's python3).
"""
import argparse
import hashlib
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import time
import urllib.parse

ARGS = None


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def expected_scene_id(path):
    """The scene id rule of luxel.proto, computed here independently of the
    CLI: the main file's sha256 without external resources, else the sha256
    of a manifest of the main hash and each resource sorted by uri."""
    main = sha256_file(path)
    if not path.endswith(".gltf"):
        return main
    with open(path, encoding="utf-8") as f:
        gltf = json.load(f)
    uris = {item["uri"] for array in ("buffers", "images") for item in gltf.get(array, [])
            if "uri" in item and not item["uri"].startswith("data:")}
    if not uris:
        return main
    manifest = f"luxel-scene-v1\n{main}\n".encode()
    for uri in sorted(uris, key=lambda u: u.encode()):
        res = os.path.join(os.path.dirname(path), urllib.parse.unquote(uri))
        manifest += f"{uri}\t{os.path.getsize(res)}\t{sha256_file(res)}\n".encode()
    return hashlib.sha256(manifest).hexdigest()


def check(cond, what):
    if not cond:
        raise AssertionError(what)


def luxel(*args, rc=0, env=None):
    """Runs the CLI; checks its exit code; returns (stdout, stderr)."""
    cmd = [ARGS.luxel] + [str(a) for a in args]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
    if p.returncode != rc:
        raise AssertionError(
            f"{' '.join(cmd)}: exit {p.returncode}, expected {rc}\n"
            f"stdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    return p.stdout, p.stderr


def json_lines(text):
    return [json.loads(line) for line in text.splitlines() if line.strip()]


class Daemon:
    """One luxeld process started by this test (and only it is stopped)."""

    def __init__(self, name, extra=(), env=None):
        self.port = free_port()
        self.server = f"127.0.0.1:{self.port}"
        data = os.path.join(ARGS.work, name)
        self.log = open(os.path.join(ARGS.work, name + ".log"), "w")
        self.proc = subprocess.Popen(
            [ARGS.luxeld, "--listen", self.server, "--data-dir", data] + list(extra),
            stdout=self.log, stderr=subprocess.STDOUT, env=dict(os.environ, **(env or {})))

    def wait_ready(self, *client_args):
        deadline = time.time() + 60
        while time.time() < deadline:
            if self.proc.poll() is not None:
                raise AssertionError(f"luxeld exited with {self.proc.returncode}; see {self.log.name}")
            p = subprocess.run([ARGS.luxel, "list", "--server", self.server, "--timeout", "2"]
                               + list(client_args), capture_output=True, text=True)
            if p.returncode == 0:
                return
            time.sleep(0.2)
        raise AssertionError(f"luxeld at {self.server} did not answer within 60 s")

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()


def test_main_flow(d):
    s = ["--server", d.server]
    scene_sha = expected_scene_id(ARGS.scene)

    # upload: the scene id covers the main file and its resources.
    out, _ = luxel("upload", ARGS.scene, "--name", "cornell", "--json", *s)
    info = json_lines(out)
    check(len(info) == 1 and info[0]["scene_id"] == scene_sha, f"upload --json: {out}")
    check(info[0]["statistics"]["triangles"] not in ("0", 0), "upload: no triangles in statistics")
    out, _ = luxel("upload", ARGS.scene, *s)
    check(scene_sha in out, f"upload (human) does not print the scene id: {out}")

    # bake: the scene is already there (no upload), watch, download, verify.
    out_dir = os.path.join(ARGS.work, "out")
    snaps = os.path.join(ARGS.work, "snaps")
    out, _ = luxel("bake", ARGS.scene, "--samples", 8, "--resolution", 32, "--out", out_dir,
                   "--snapshot-interval", 0.05, "--snapshots", snaps, "--json", *s)
    lines = json_lines(out)
    kinds = [l["type"] for l in lines]
    check(kinds[0] == "scene" and lines[0]["uploaded"] is False,
          f"bake re-uploaded a stored scene: {lines[0]}")
    check(kinds[1] == "bake" and "event" in kinds and kinds[-1] == "result", f"bake --json kinds: {kinds}")
    bake_id = lines[1]["bake"]["bake_id"]
    check(lines[-1]["bake"]["state"] == "BAKE_STATE_SUCCEEDED", f"bake result: {lines[-1]}")
    finals = [l for l in lines if l["type"] == "event" and l["final"]]
    check(len(finals) == 1, "exactly one final event")
    artifacts = [l for l in lines if l["type"] == "artifact"]
    check({a["name"] for a in artifacts} == set(lines[-1]["bake"]["artifacts"]) and artifacts,
          f"downloaded {[a['name'] for a in artifacts]}")
    for a in artifacts:
        path = os.path.join(out_dir, a["name"])
        check(os.path.isfile(path) and sha256_file(path) == a["sha256"], f"artifact {path} verifies")
        check(os.path.getsize(path) == a["size"] and a["size"] > 0, f"artifact {path} size")
    check("irradiance.exr" in {a["name"] for a in artifacts}, "irradiance.exr downloaded")
    check(not [f for f in os.listdir(out_dir) if f.endswith(".part")], "no .part files left")
    for l in lines:
        if l.get("snapshot_file"):
            check(os.path.isfile(l["snapshot_file"]), f"snapshot {l['snapshot_file']} written")

    # The same bake in-process gives the same bits as through luxeld: the
    # settings reach the engine alike on both paths (pixels compared; the
    # files' metadata names where the scene came from).
    local_dir = os.path.join(ARGS.work, "local")
    luxel("bake", ARGS.scene, "--samples", 8, "--resolution", 32, "--out", local_dir, "--local")
    for name in ("irradiance.exr", "samples.exr"):
        diff = subprocess.run(["idiff", "-fail", "0", "-warn", "0", os.path.join(out_dir, name),
                               os.path.join(local_dir, name)], capture_output=True, text=True)
        check(diff.returncode == 0, f"{name}: remote and local bakes differ:\n{diff.stdout}")

    # list / status
    out, _ = luxel("list", "--json", *s)
    bakes = {b["bake_id"]: b for b in json_lines(out)}
    check(bake_id in bakes and bakes[bake_id]["state"] == "BAKE_STATE_SUCCEEDED", f"list: {out}")
    out, _ = luxel("list", "--state", "running,queued", "--json", *s)
    check(bake_id not in out, "list --state running,queued excludes the finished bake")
    out, _ = luxel("list", "--scenes", "--json", *s)
    check(scene_sha in {x["scene_id"] for x in json_lines(out)}, "list --scenes")
    out, _ = luxel("status", bake_id, *s)
    check("SUCCEEDED" in out and bake_id in out, f"status: {out}")

    # fetch: all artifacts again, byte-identical; then a single one.
    again = os.path.join(ARGS.work, "fetched")
    luxel("fetch", bake_id, "--out", again, *s)
    for a in artifacts:
        check(sha256_file(os.path.join(again, a["name"])) == a["sha256"], f"fetch {a['name']}")
    one = os.path.join(ARGS.work, "one")
    luxel("fetch", bake_id, "--out", one, "--artifact", "manifest.json", *s)
    check(os.listdir(one) == ["manifest.json"], f"fetch --artifact: {os.listdir(one)}")

    # --detach prints only the id; watch follows it to the end; cancel of a
    # finished bake is a no-op that succeeds.
    out, _ = luxel("bake", scene_sha, "--samples", 8, "--resolution", 32, "--seed", 7, "--detach", *s)
    detached = out.strip()
    check(len(detached) > 0 and "\n" not in detached, f"--detach output: {out!r}")
    luxel("watch", detached, "--quiet", *s)
    out, _ = luxel("cancel", detached, "--json", *s)
    check(json_lines(out)[0]["state"] == "BAKE_STATE_SUCCEEDED", "cancel of a finished bake")
    return bake_id


def test_probes(d):
    """Light probes from a positions file: the remote CLI sends the positions,
    the daemon serves probes.bin/json only (lightmap off), and they equal the
    in-process bake's bit for bit."""
    s = ["--server", d.server]
    positions = os.path.join(ARGS.work, "probes_in.json")
    with open(positions, "w") as f:
        json.dump({"probes": [[0, 1, 0], {"position": [0.2, 0.5, -0.1]}, [-0.3, 1.2, 0.3]]}, f)
    args = ["--probes", "file:" + positions, "--no-lightmap", "--samples", 32]
    remote = os.path.join(ARGS.work, "probes_remote")
    out, _ = luxel("bake", ARGS.scene, *args, "--out", remote, "--json", *s)
    lines = json_lines(out)
    check(lines[-1]["bake"]["state"] == "BAKE_STATE_SUCCEEDED", f"probe bake: {lines[-1]}")
    names = {l["name"] for l in lines if l["type"] == "artifact"}
    check(names == {"probes.bin", "probes.json"}, f"probe artifacts: {names}")
    local = os.path.join(ARGS.work, "probes_local")
    luxel("bake", ARGS.scene, *args, "--out", local, "--local")
    check(sha256_file(os.path.join(remote, "probes.bin")) ==
          sha256_file(os.path.join(local, "probes.bin")), "remote and local probes.bin differ")
    with open(os.path.join(remote, "probes.json")) as f:
        meta = json.load(f)
    check(meta["layout"]["mode"] == "file" and len(meta["probes"]) == 3, f"probes.json: {meta['layout']}")


def test_one_job_both_paths(d):
    """The CLI's --local mode and the daemon run the same job (the engine's
    job module): a lightmap + probes + denoise job gives the same files with
    the same bytes either way. The manifest, the error series and probes.json
    carry run times (and the daemon's scene id), so they are compared by
    their fields."""
    s = ["--server", d.server]
    # A scene of its own (one more byte), so the daemon stores it under its
    # file name, the name a local bake gives it too (not an earlier --name).
    folder = os.path.join(ARGS.work, "job_scene")
    os.makedirs(folder)
    scene = os.path.join(folder, os.path.basename(ARGS.scene))
    with open(ARGS.scene, "rb") as f:
        gltf = f.read()
    with open(scene, "wb") as f:
        f.write(gltf + b"\n")
    with open(ARGS.scene, encoding="utf-8") as f:
        bin_uri = json.load(f)["buffers"][0]["uri"]
    shutil.copyfile(os.path.join(os.path.dirname(ARGS.scene), bin_uri), os.path.join(folder, bin_uri))
    positions = os.path.join(ARGS.work, "job_probes.json")
    with open(positions, "w") as f:
        json.dump({"probes": [[0, 1, 0], [0.2, 0.5, -0.1]]}, f)
    args = ["--probes", "file:" + positions, "--denoise", "atrous", "--samples", 32,
            "--resolution", 64]
    remote = os.path.join(ARGS.work, "job_remote")
    out, _ = luxel("bake", scene, *args, "--out", remote, "--json", *s)
    check(json_lines(out)[-1]["bake"]["state"] == "BAKE_STATE_SUCCEEDED", f"job: {out[-500:]}")
    local = os.path.join(ARGS.work, "job_local")
    luxel("bake", scene, *args, "--out", local, "--local")
    names = set(os.listdir(remote))
    check(names == set(os.listdir(local)), f"files: remote {sorted(names)}, local {sorted(os.listdir(local))}")
    for required in ("irradiance.exr", "irradiance_denoised.exr", "probes.bin", "probes.json"):
        check(required in names, f"{required} missing from {sorted(names)}")
    timed = {"manifest.json", "error_series.csv", "probes.json"}
    differ = [n for n in sorted(names - timed)
              if sha256_file(os.path.join(remote, n)) != sha256_file(os.path.join(local, n))]
    check(not differ, f"remote and local differ in {differ}")
    with open(os.path.join(remote, "manifest.json")) as f:
        m_remote = json.load(f)
    with open(os.path.join(local, "manifest.json")) as f:
        m_local = json.load(f)
    for key in ("width", "height", "encodings", "features"):
        check(m_remote.get(key) == m_local.get(key), f"manifest {key}: {m_remote.get(key)} vs {m_local.get(key)}")
    with open(os.path.join(remote, "probes.json")) as f:
        p_remote = json.load(f)
    with open(os.path.join(local, "probes.json")) as f:
        p_local = json.load(f)
    check(p_remote["probes"] == p_local["probes"], "probes.json: the probes differ")


def test_changed_buffer_is_uploaded(d, original_id):
    """The same .gltf beside a changed .bin is another scene: `luxel bake`
    must upload it rather than reuse the stored scene with the old buffer."""
    s = ["--server", d.server]
    folder = os.path.join(ARGS.work, "changed")
    os.makedirs(folder)
    gltf = os.path.join(folder, os.path.basename(ARGS.scene))
    shutil.copyfile(ARGS.scene, gltf)
    with open(ARGS.scene, encoding="utf-8") as f:
        bin_uri = json.load(f)["buffers"][0]["uri"]
    with open(os.path.join(os.path.dirname(ARGS.scene), bin_uri), "rb") as f:
        data = bytearray(f.read())
    # cornell_box.bin: accessor 0 (POSITION) at byte 0, 40-byte stride. Nudge
    # vertex 0's y toward the middle of its [0, 5.488] range: still valid.
    (y,) = struct.unpack_from("<f", data, 4)
    struct.pack_into("<f", data, 4, 0.99 * y + 0.01 * 2.744)
    with open(os.path.join(folder, bin_uri), "wb") as f:
        f.write(data)
    changed_id = expected_scene_id(gltf)
    check(changed_id != original_id, "a changed .bin changes the expected scene id")

    out, _ = luxel("bake", gltf, "--samples", 8, "--resolution", 32, "--detach", "--json", *s)
    lines = json_lines(out)
    check(lines[0]["type"] == "scene" and lines[0]["uploaded"] is True,
          f"bake reused a stored scene for a changed .bin: {lines[0]}")
    check(lines[0]["scene"]["scene_id"] == changed_id, f"changed scene id: {lines[0]}")
    check(lines[1]["bake"]["scene_id"] == changed_id, f"bake of the changed scene: {lines[1]}")
    luxel("watch", lines[1]["bake"]["bake_id"], "--quiet", *s)
    out, _ = luxel("list", "--scenes", "--json", *s)
    stored = {x["scene_id"] for x in json_lines(out)}
    check({original_id, changed_id} <= stored, f"both scenes stored: {stored}")
    # The CLI's own upload agrees with the rule too.
    out, _ = luxel("upload", gltf, "--json", *s)
    info = json_lines(out)[0]
    check(info["scene_id"] == changed_id and info.get("already_stored") is True, f"re-upload: {info}")


def test_errors(d):
    s = ["--server", d.server]
    _, err = luxel("status", "0123456789abcdef0123456789abcdef", *s, rc=1)
    check("NOT_FOUND" in err, f"unknown bake: {err}")
    _, err = luxel("list", "--server", f"127.0.0.1:{free_port()}", rc=1)
    check("cannot reach luxeld" in err and "UNAVAILABLE" in err, f"no daemon: {err}")
    luxel("bake", ARGS.scene, *s, rc=2)                        # no --out
    luxel("bake", ARGS.scene, "--out", "x", "--clamp", 2, *s, rc=2)  # local-only setting
    _, err = luxel("bake", ARGS.scene, "--out", "x", "--bounces", 99, *s, rc=2)  # invalid setting
    # The daemon and the Python client report the same words (tests/python).
    check("settings.max_bounces: must be in [0, 64], got 99" in err, f"--bounces 99: {err}")
    _, err = luxel("bake", ARGS.scene, "--out", "x", "--dilate", 0, *s, rc=2)  # API reads 0 as 2
    check("settings.dilation_texels: 0 cannot be sent" in err, f"--dilate 0: {err}")
    luxel("list", "--state", "sleeping", *s, rc=2)
    luxel("frobnicate", rc=2)
    _, err = luxel("upload", os.path.join(ARGS.work, "missing.gltf"), *s, rc=1)
    check("missing.gltf" in err, f"missing file: {err}")
    # A cancelled bake: exit 3 from watch.
    out, _ = luxel("bake", ARGS.scene, "--samples", 0, "--time", 60, "--resolution", 32,
                   "--detach", *s)
    bake_id = out.strip()
    luxel("cancel", bake_id, *s)
    _, err = luxel("watch", bake_id, "--quiet", *s, rc=3)
    check("CANCELLED" in err, f"watch of a cancelled bake: {err}")


def test_token():
    # The daemon's token never goes on its command line (ps shows argv to
    # every user): --token is refused, an empty LUXELD_TOKEN too.
    for args, env, why in ((["--token", "s3cret"], {}, "--token: not accepted on the command line"),
                           ([], {"LUXELD_TOKEN": ""}, "LUXELD_TOKEN is set but empty")):
        p = subprocess.run([ARGS.luxeld, "--data-dir", os.path.join(ARGS.work, "token-refused")]
                           + args, capture_output=True, text=True, env=dict(os.environ, **env),
                           timeout=30)
        check(p.returncode == 2 and why in p.stderr, f"luxeld {args} {env}: {p.returncode} {p.stderr}")
    d = Daemon("token", env={"LUXELD_TOKEN": "s3cret"})
    try:
        d.wait_ready("--token", "s3cret")
        _, err = luxel("list", "--server", d.server, rc=1)
        check("UNAUTHENTICATED" in err, f"missing token: {err}")
        env = dict(os.environ, LUXEL_TOKEN="s3cret", LUXEL_SERVER=d.server)
        luxel("list", env=env)
    finally:
        d.stop()


def test_tls():
    cert, key = os.path.join(ARGS.work, "cert.pem"), os.path.join(ARGS.work, "key.pem")
    openssl = shutil.which("openssl")
    if not openssl:
        print("skip TLS: no openssl binary")
        return
    subprocess.run([openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
                    "-subj", "/CN=localhost", "-addext", "subjectAltName=IP:127.0.0.1,DNS:localhost",
                    "-keyout", key, "-out", cert], check=True, capture_output=True)
    d = Daemon("tls", ["--tls-cert", cert, "--tls-key", key])
    try:
        d.wait_ready("--tls-ca", cert)
        luxel("upload", ARGS.scene, "--server", d.server, "--tls-ca", cert)
        luxel("list", "--server", d.server, "--timeout", 3, rc=1)  # plaintext to a TLS port
    finally:
        d.stop()


def main():
    global ARGS
    ap = argparse.ArgumentParser()
    ap.add_argument("--luxel", required=True)
    ap.add_argument("--luxeld", required=True)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--work", required=True)
    ARGS = ap.parse_args()
    shutil.rmtree(ARGS.work, ignore_errors=True)
    os.makedirs(ARGS.work)
    d = Daemon("data")
    try:
        d.wait_ready()
        test_main_flow(d)
        test_probes(d)
        test_one_job_both_paths(d)
        test_changed_buffer_is_uploaded(d, expected_scene_id(ARGS.scene))
        test_errors(d)
    finally:
        d.stop()
    test_token()
    test_tls()
    print("cli_e2e: all checks passed")


if __name__ == "__main__":
    try:
        main()
    except AssertionError as e:
        print(f"FAILED: {e}", file=sys.stderr)
        sys.exit(1)
