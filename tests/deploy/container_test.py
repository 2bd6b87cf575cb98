"""deploy/container/: the Containerfile is linted (no image builder or
registry is reachable here, so it is not built) and entrypoint.sh runs the
real luxeld built in the tree: it starts from environment variables, answers
the gRPC health check the image's HEALTHCHECK runs, keeps the token off the
command line, and stops with status 0 on SIGTERM.

usage: container_test.py --luxeld BIN --luxel BIN [--cache DIR]
"""
import argparse
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest
import urllib.request

ARGS = None
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CONTAINERFILE = os.path.join(ROOT, "deploy", "container", "Containerfile")
ENTRYPOINT = os.path.join(ROOT, "deploy", "container", "entrypoint.sh")


def instructions(text):
    """[(INSTRUCTION, arguments)] with continuation lines joined."""
    out, pending = [], ""
    for line in text.splitlines():
        if not pending and (not line.strip() or line.lstrip().startswith("#")):
            continue
        if line.lstrip().startswith("#"):
            continue  # a comment inside a continued instruction
        pending += line.rstrip()
        if pending.endswith("\\"):
            pending = pending[:-1] + " "
            continue
        word, _, rest = pending.strip().partition(" ")
        out.append((word.upper(), rest.strip()))
        pending = ""
    return out


def stages(instrs):
    """[{'from': image, 'name': alias, 'instrs': [...]}] with ARG defaults resolved."""
    args, result = {}, []
    for word, rest in instrs:
        if word == "ARG" and not result:
            k, _, v = rest.partition("=")
            args[k] = v
        elif word == "FROM":
            image = re.sub(r"\$\{(\w+)\}", lambda m: args.get(m.group(1), ""), rest.split()[0])
            name = rest.split()[2] if len(rest.split()) == 3 and rest.split()[1].upper() == "AS" else None
            result.append({"from": image, "name": name, "instrs": []})
        elif result:
            result[-1]["instrs"].append((word, rest))
    return result


def apt_packages(run):
    """Packages an `apt-get install` in a RUN line names."""
    m = re.search(r"apt-get install ([^&;|]*)", run)
    return [w for w in m.group(1).split() if not w.startswith("-")] if m else []


def lint(text):
    """Problems of a Containerfile against the rules of deploy/container/."""
    problems = []
    st = stages(instructions(text))
    if len(st) < 2:
        return ["multi-stage build expected (build + runtime)"]
    for s in st:
        image = s["from"]
        if not re.fullmatch(r"(docker\.io/(library/)?)?debian:bookworm[\w.-]*(@sha256:[0-9a-f]{64})?",
                            image):
            problems.append(f"FROM {image}: only Debian 12 (bookworm) images")
        if image.endswith(":latest") or ":" not in image:
            problems.append(f"FROM {image}: untagged or latest")
    build_runs = " ".join(r for w, r in st[0]["instrs"] if w == "RUN")
    for script in ("deploy/install-deps.sh", "deploy/build.sh"):
        if script not in build_runs:
            problems.append(f"build stage does not run {script}")
    runtime = st[-1]["instrs"]
    words = [w for w, _ in runtime]
    for w, r in runtime + st[0]["instrs"]:
        if w == "RUN" and re.search(r"\b(pip3?|curl|wget|npm|go get|gem)\b", r):
            problems.append(f"RUN fetches outside apt: {r[:60]}")
        if w == "ADD" and "://" in r:
            problems.append("ADD from a URL")
    users = [r for w, r in runtime if w == "USER"]
    if not users or users[-1].split(":")[0] in ("root", "0"):
        problems.append(f"last USER must be a non-root user, got {users}")
    elif not users[-1].split(":")[0].isdigit():
        problems.append("USER must be numeric (runAsNonRoot can only check a number)")
    for required in ("VOLUME", "EXPOSE", "HEALTHCHECK", "ENTRYPOINT", "STOPSIGNAL"):
        if required not in words:
            problems.append(f"{required} missing in the runtime stage")
    env = " ".join(r for w, r in runtime if w == "ENV")
    data = re.search(r"LUXELD_DATA_DIR=(\S+)", env)
    volume = " ".join(r for w, r in runtime if w == "VOLUME")
    if not data or data.group(1) not in volume:
        problems.append("VOLUME is not LUXELD_DATA_DIR")
    listen = re.search(r"LUXELD_LISTEN=\S+:(\d+)", env)
    metrics = re.search(r"LUXELD_METRICS_LISTEN=\S+:(\d+)", env)
    exposed = " ".join(r for w, r in runtime if w == "EXPOSE")
    for m in (listen, metrics):
        if not m or not re.search(rf"\b{m.group(1)}(/tcp)?\b", exposed):
            problems.append(f"EXPOSE {exposed!r} lacks a port of LUXELD_LISTEN/METRICS")
    health = " ".join(r for w, r in runtime if w == "HEALTHCHECK")
    if "luxel health" not in health:
        problems.append("HEALTHCHECK does not use `luxel health` (grpc.health.v1)")
    if "SIGTERM" not in " ".join(r for w, r in runtime if w == "STOPSIGNAL"):
        problems.append("STOPSIGNAL must be SIGTERM (luxeld checkpoints on it)")
    if not any(w == "RUN" and apt_packages(r) for w, r in runtime):
        problems.append("runtime stage installs no Debian packages")
    return problems


def runtime_packages(text):
    st = stages(instructions(text))
    return [p for w, r in st[-1]["instrs"] if w == "RUN" for p in apt_packages(r)]


def healthcheck_command(text):
    st = stages(instructions(text))
    h = [r for w, r in st[-1]["instrs"] if w == "HEALTHCHECK"][0]
    return h.split(" CMD ", 1)[1]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class ContainerfileLint(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with open(CONTAINERFILE) as f:
            cls.text = f.read()

    def test_lint_passes(self):
        self.assertEqual(lint(self.text), [])

    def test_lint_rejects_broken_files(self):
        broken = {
            "USER 10001:10001": "USER root",
            "bookworm-slim": "latest",
            "deploy/install-deps.sh &&": "pip install luxel &&",
            "HEALTHCHECK": "#HEALTHCHECK",
            "EXPOSE 50051/tcp 9464/tcp": "EXPOSE 8080",
            'VOLUME ["/var/lib/luxel"]': "VOLUME /data",
        }
        for old, new in broken.items():
            self.assertIn(old, self.text)
            self.assertNotEqual(lint(self.text.replace(old, new)), [], new)

    @unittest.skipUnless(shutil.which("apt-cache") and shutil.which("dpkg-query"), "not Debian")
    def test_runtime_packages_cover_every_linked_library(self):
        # Independent of the Containerfile: ldd of the binaries, the Debian
        # package owning each library (dpkg -S), against the closure of the
        # runtime stage's package list (apt-cache depends --recurse).
        def closure(pkgs):
            r = subprocess.run(["apt-cache", "depends", "--recurse", "--no-recommends",
                                "--no-suggests", "--no-conflicts", "--no-breaks",
                                "--no-replaces", "--no-enhances", "--no-pre-depends", *pkgs],
                               capture_output=True, text=True, timeout=60)
            self.assertEqual(r.returncode, 0, r.stderr)
            names = set(re.findall(r"^(\S+)$", r.stdout, re.M))
            names |= set(re.findall(r"Depends: <?([\w.+-]+)", r.stdout))
            return {n.split(":")[0] for n in names}

        paths = set()
        for binary in (ARGS.luxeld, ARGS.luxel):
            ldd = subprocess.run(["ldd", binary], capture_output=True, text=True, timeout=30)
            self.assertEqual(ldd.returncode, 0, ldd.stderr)
            self.assertNotIn("not found", ldd.stdout)
            paths |= {os.path.realpath(p) for p in re.findall(r"=> (/\S+)", ldd.stdout)}
        # One dpkg -S for all (some 300 libraries: OpenImageIO brings many).
        # dpkg knows /usr/lib/... paths; usrmerge may resolve them to /lib/...
        # or the other way round, so both spellings are asked.
        queries = sorted(paths | {p[4:] if p.startswith("/usr/") else "/usr" + p for p in paths})
        owner = subprocess.run(["dpkg", "-S", *queries], capture_output=True, text=True, timeout=60)
        owned = {}
        for line in owner.stdout.splitlines():
            pkgs, _, path = line.partition(": ")
            for pkg in pkgs.split(", "):
                owned.setdefault(path, pkg.split(":")[0])
        needed = set()
        for p in paths:
            alt = p[4:] if p.startswith("/usr/") else "/usr" + p
            self.assertTrue(p in owned or alt in owned, f"{p}: no Debian package owns it")
            needed.add(owned.get(p) or owned[alt])
        pkgs = runtime_packages(self.text)
        self.assertEqual(sorted(needed - closure(pkgs)), [])
        without_embree = [p for p in pkgs if p != "libembree3-3"]
        self.assertIn("libembree3-3", needed - closure(without_embree))
        # Every name is a package of this Debian (12, like the image).
        r = subprocess.run(["apt-cache", "show", "--no-all-versions", *pkgs],
                           capture_output=True, text=True, timeout=60)
        known = set(re.findall(r"^Package: (\S+)$", r.stdout, re.M))
        self.assertEqual(sorted(set(pkgs) - known), [])


class EntrypointRun(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="luxeld-entry-")
        self.port = free_port()
        self.token = "s3cret-" + str(os.getpid())
        self.token_file = os.path.join(self.tmp, "token")
        with open(self.token_file, "w") as f:
            f.write(self.token + "\n")
        os.chmod(self.token_file, 0o600)  # luxeld refuses a token file others can read
        bin_dir = os.path.join(self.tmp, "bin")
        os.mkdir(bin_dir)  # luxeld and luxel on PATH, as in the image
        os.symlink(os.path.abspath(ARGS.luxeld), os.path.join(bin_dir, "luxeld"))
        os.symlink(os.path.abspath(ARGS.luxel), os.path.join(bin_dir, "luxel"))
        self.env = {
            "PATH": bin_dir + ":/usr/bin:/bin",
            "LUXELD_LISTEN": f"127.0.0.1:{self.port}",
            "LUXELD_DATA_DIR": os.path.join(self.tmp, "data"),
            "LUXELD_TOKEN_FILE": self.token_file,
            "LUXELD_METRICS_LISTEN": "",
            "LUXEL_CACHE_DIR": ARGS.cache or os.path.join(self.tmp, "cache"),
            "POCL_CACHE_DIR": os.path.join(ARGS.cache or os.path.join(self.tmp, "cache"), "pocl"),
            "LUXEL_DEVICE": os.environ.get("LUXEL_DEVICE", ""),
        }
        self.proc = None

    def tearDown(self):
        if self.proc and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def luxel(self, *args, env=None):
        return subprocess.run([ARGS.luxel, *args, "--server", f"127.0.0.1:{self.port}"],
                              capture_output=True, text=True, timeout=30, env=env or self.env)

    def start(self, **overrides):
        env = dict(self.env, **overrides)
        self.proc = subprocess.Popen([ENTRYPOINT], env=env, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        return env

    def wait_healthy(self, timeout=60):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                self.fail("luxeld exited: " + self.proc.stderr.read())
            if self.luxel("health", "--timeout", "2").returncode == 0:
                return
            time.sleep(0.2)
        self.fail("luxel health never said SERVING")

    def test_starts_answers_health_and_stops_on_sigterm(self):
        self.start()
        self.wait_healthy()
        # exec: the entrypoint's process is luxeld itself, so SIGTERM reaches it.
        self.assertEqual(os.path.realpath(f"/proc/{self.proc.pid}/exe"),
                         os.path.realpath(ARGS.luxeld))
        with open(f"/proc/{self.proc.pid}/cmdline", "rb") as f:
            argv = f.read().split(b"\0")
        self.assertNotIn(self.token.encode(), b" ".join(argv))
        self.assertIn(self.env["LUXELD_LISTEN"].encode(), argv)
        self.assertTrue(os.path.exists(os.path.join(self.env["LUXELD_DATA_DIR"], "luxeld.lock")))
        # The image's HEALTHCHECK command, run by sh as the runtime would.
        with open(CONTAINERFILE) as f:
            check = healthcheck_command(f.read())
        r = subprocess.run(["/bin/sh", "-c", check], env=self.env, capture_output=True,
                           text=True, timeout=30)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        whole = self.luxel("health", "--service", "")  # Kubernetes' liveness probe
        self.assertEqual(whole.returncode, 0, whole.stderr)
        unknown = self.luxel("health", "--service", "no.such.Service")
        self.assertEqual(unknown.returncode, 1)
        self.assertIn("NOT_FOUND", unknown.stderr)
        # Health needs no token (probes carry none); the Luxel API does.
        denied = self.luxel("list")
        self.assertEqual(denied.returncode, 1)
        self.assertIn("UNAUTHENTICATED", denied.stderr)
        allowed = self.luxel("list", "--token", self.token)
        self.assertEqual(allowed.returncode, 0, allowed.stderr)
        self.proc.send_signal(signal.SIGTERM)
        _, err = self.proc.communicate(timeout=30)
        self.assertEqual(self.proc.returncode, 0, err)
        self.assertIn("event=stopped", err)
        # Gone: health now fails (exit 1), as a probe would see it.
        self.assertEqual(self.luxel("health", "--timeout", "2").returncode, 1)

    def test_metrics_port_from_the_environment(self):
        help_text = subprocess.run([ARGS.luxeld, "--help"], capture_output=True, text=True).stdout
        if "--metrics-listen" not in help_text:
            self.skipTest("this luxeld has no --metrics-listen")
        metrics = free_port()
        self.start(LUXELD_METRICS_LISTEN=f"127.0.0.1:{metrics}")
        self.wait_healthy()
        with urllib.request.urlopen(f"http://127.0.0.1:{metrics}/metrics", timeout=10) as r:
            body = r.read().decode()
        self.assertIn("luxel_queue_depth", body)
        self.proc.send_signal(signal.SIGTERM)
        self.proc.communicate(timeout=30)
        self.assertEqual(self.proc.returncode, 0)

    def test_refuses_to_start_without_a_token(self):
        self.start(LUXELD_TOKEN_FILE="")
        _, err = self.proc.communicate(timeout=30)
        self.assertEqual(self.proc.returncode, 2)
        self.assertIn("LUXELD_ALLOW_NO_TOKEN", err)
        self.start(LUXELD_TOKEN_FILE=os.path.join(self.tmp, "missing"))
        _, err = self.proc.communicate(timeout=30)
        self.assertEqual(self.proc.returncode, 2)
        self.assertIn("cannot be read", err)

    def test_extra_args_reach_luxeld(self):
        # A flag luxeld rejects proves the variable is passed through (exit 2).
        self.start(LUXELD_EXTRA_ARGS="--max-queued 0")
        _, err = self.proc.communicate(timeout=30)
        self.assertEqual(self.proc.returncode, 2, err)
        self.assertIn("--max-queued", err)

    @unittest.skipUnless(shutil.which("shellcheck"), "shellcheck not installed")
    def test_shellcheck(self):
        r = subprocess.run(["shellcheck", ENTRYPOINT], capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stdout)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--luxeld", required=True)
    p.add_argument("--luxel", required=True)
    p.add_argument("--cache")
    ARGS, rest = p.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
