"""luxeld under two restrictions of deploy/systemd/luxeld.service that could
break it, emulated by sandbox_exec (sandbox_exec.c: the seccomp rules
systemd 252 installs) since no systemd starts units here:

- MemoryDenyWriteExecute=yes against PoCL's kernel JIT (it writes a shared
  object to POCL_CACHE_DIR and dlopen()s it);
- RestrictAddressFamilies=AF_UNIX AF_INET AF_INET6 against gRPC (--listen
  127.0.0.1:PORT: a literal address, because what "localhost" resolves to, and
  how long that takes, depends on the build machine's /etc/hosts and DNS:
  a CI machine once never served within 30 s with it);
- where mount namespaces are allowed (root), ProtectSystem=strict,
  PrivateTmp and ProtectHome through protect_system.sh: luxeld writes
  nothing outside its data dir and cache dirs.

Controls first: under the filter a W+X mapping and a netlink socket must
fail, else the filter proves nothing. Then luxeld runs under it with an
empty POCL_CACHE_DIR and bakes the Cornell box through the CLI.

usage: sandbox_test.py --sandbox-exec BIN --luxeld BIN --luxel BIN --scene GLTF --unit FILE
                       --work DIR (not under /tmp: PrivateTmp hides it)
"""
import argparse
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

ARGS = None
PROTECT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "protect_system.sh")


def mount_namespaces_work():
    if not shutil.which("unshare"):
        return False
    r = subprocess.run(["unshare", "-m", "--propagation", "private", "true"],
                       capture_output=True, timeout=30)
    return r.returncode == 0


HIDDEN = ("/tmp", "/root", "/home", "/run/user")  # emptied by PrivateTmp / ProtectHome


def tree_hidden():
    """The first file-system view protect_system.sh would hide that the test's own
    binaries, scene or work dir lie in (a checkout under /tmp or a home), or None:
    the emulation cannot run them from there."""
    for path in (ARGS.work, ARGS.luxeld, ARGS.luxel, ARGS.scene, PROTECT):
        real = os.path.realpath(path)
        for h in HIDDEN:
            if real == h or real.startswith(h + "/"):
                return h
    return None


def can_protect():
    return mount_namespaces_work() and tree_hidden() is None


def protected(writable, cmd):
    """cmd under protect_system.sh when mount namespaces work and the tree is
    visible under it, else as is."""
    if not can_protect():
        return cmd
    return ["unshare", "-m", "--propagation", "private", "sh", PROTECT, *writable, "--", *cmd]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Sandbox(unittest.TestCase):
    def run_py(self, code, sandboxed):
        cmd = [sys.executable, "-c", code]
        return subprocess.run([ARGS.sandbox_exec, *cmd] if sandboxed else cmd,
                              capture_output=True, text=True, timeout=30)

    def test_filter_refuses_writable_executable_memory(self):
        code = "import mmap; mmap.mmap(-1, 4096, prot=mmap.PROT_READ | mmap.PROT_WRITE | mmap.PROT_EXEC)"
        self.assertEqual(self.run_py(code, False).returncode, 0)
        r = self.run_py(code, True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("PermissionError", r.stderr)

    def test_filter_refuses_other_address_families(self):
        code = "import socket; socket.socket(socket.AF_NETLINK, socket.SOCK_RAW, 0)"
        self.assertEqual(self.run_py(code, False).returncode, 0)
        r = self.run_py(code, True)
        self.assertIn("Address family not supported", r.stderr)
        ok = "import socket; socket.socket(socket.AF_INET6); socket.socket(socket.AF_UNIX)"
        self.assertEqual(self.run_py(ok, True).returncode, 0)

    def test_protect_system_leaves_only_the_given_dirs_writable(self):
        if not mount_namespaces_work():
            self.skipTest("no mount namespaces (not root)")
        if tree_hidden():
            self.skipTest("the build tree lies under %s, which PrivateTmp/ProtectHome hide" % tree_hidden())
        work = tempfile.mkdtemp(prefix="protect-", dir=ARGS.work)
        try:
            ok, other = os.path.join(work, "state"), os.path.join(work, "elsewhere")
            os.mkdir(other)
            script = f"touch {ok}/f && ! touch {other}/f 2>/dev/null && ! touch /usr/.luxel-probe 2>/dev/null && touch /tmp/f && [ -z \"$(ls -A /root)\" ]"
            r = subprocess.run(protected([ok], ["sh", "-c", script]), capture_output=True,
                               text=True, timeout=30)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertTrue(os.path.exists(os.path.join(ok, "f")))
            self.assertFalse(os.path.exists(os.path.join(other, "f")))
        finally:
            shutil.rmtree(work, ignore_errors=True)

    def test_luxeld_bakes_under_the_filter(self):
        tmp = tempfile.mkdtemp(prefix="luxeld-sandbox-", dir=ARGS.work)
        port = free_port()
        data, pocl = os.path.join(tmp, "data"), os.path.join(tmp, "pocl")
        program_cache = os.environ.get("LUXEL_CACHE_DIR") or os.path.join(tmp, "programs")
        env = dict(os.environ, POCL_CACHE_DIR=pocl, LUXEL_CACHE_DIR=program_cache)
        cmd = [ARGS.sandbox_exec, ARGS.luxeld, "--data-dir", data, "--listen", f"127.0.0.1:{port}"]
        # The log goes to a file, not a pipe nobody reads while the bake runs
        # (a full pipe would block luxeld).
        log = open(os.path.join(tmp, "luxeld.log"), "w+")
        proc = subprocess.Popen(protected([data, pocl, program_cache], cmd), env=env,
                                stdout=subprocess.DEVNULL, stderr=log, text=True)

        def log_tail():
            log.flush()
            log.seek(0)
            return log.read()[-2000:]

        try:
            server = ["--server", f"127.0.0.1:{port}"]
            # Generous: a loaded 2-core CI machine starts PoCL slowly.
            deadline = time.monotonic() + 90
            while subprocess.run([ARGS.luxel, "health", *server, "--timeout", "2"],
                                 capture_output=True).returncode != 0:
                if proc.poll() is not None:
                    self.fail("luxeld exited under the filter: " + log_tail())
                if time.monotonic() > deadline:
                    self.fail("luxeld never served within 90 s: " + log_tail())
                time.sleep(0.2)
            out = os.path.join(tmp, "out")
            r = subprocess.run([ARGS.luxel, "bake", ARGS.scene, *server, "--out", out,
                                "--resolution", "32", "--samples", "2", "--bounces", "1"],
                               capture_output=True, text=True, timeout=240, env=env)
            self.assertEqual(r.returncode, 0, r.stdout[-2000:] + r.stderr[-2000:])
            self.assertTrue(os.path.getsize(os.path.join(out, "irradiance.exr")) > 0)
            jitted = [f for _, _, fs in os.walk(env["POCL_CACHE_DIR"]) for f in fs]
            self.assertTrue(jitted, "PoCL compiled nothing: its JIT was not exercised")
            proc.send_signal(signal.SIGTERM)
            proc.wait(timeout=60)
            self.assertEqual(proc.returncode, 0, log_tail())
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            log.close()
            shutil.rmtree(tmp, ignore_errors=True)

    def test_unit_sets_what_was_tested(self):
        with open(ARGS.unit) as f:
            lines = [l.strip() for l in f]
        self.assertIn("MemoryDenyWriteExecute=yes", lines)
        self.assertIn("RestrictAddressFamilies=AF_UNIX AF_INET AF_INET6", lines)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--sandbox-exec", required=True)
    p.add_argument("--luxeld", required=True)
    p.add_argument("--luxel", required=True)
    p.add_argument("--scene", required=True)
    p.add_argument("--unit", required=True)
    p.add_argument("--work", required=True)
    ARGS, rest = p.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
