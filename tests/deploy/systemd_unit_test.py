"""deploy/systemd/luxeld.service: the hardening an operator relies on is there,
systemd itself accepts the unit (systemd-analyze verify, and `security` scores
its exposure), and ExecStart names where `cmake --install` puts luxeld.

usage: systemd_unit_test.py --unit FILE --luxeld BIN --build DIR
Each check is also run on a broken copy of the unit that it must reject.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

ARGS = None


def parse_unit(text):
    """{section: [(key, value), ...]}; systemd allows a key more than once."""
    sections, current = {}, None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        m = re.fullmatch(r"\[(\w+)\]", line)
        if m:
            current = sections.setdefault(m.group(1), [])
            continue
        key, sep, value = line.partition("=")
        if not sep or current is None:
            raise ValueError(f"not 'Key=value' inside a section: {raw!r}")
        current.append((key.strip(), value.strip()))
    return sections


def values(sections, section, key):
    return [v for k, v in sections.get(section, []) if k == key]


# key -> value it must have (the last assignment wins in systemd).
REQUIRED = {
    "ProtectSystem": "strict",
    "ProtectHome": "yes",
    "PrivateTmp": "yes",
    "NoNewPrivileges": "yes",
    "CapabilityBoundingSet": "",
    "StateDirectory": "luxel",
    "DynamicUser": "yes",
    "Restart": "on-failure",
    "KillSignal": "SIGTERM",
    "LoadCredential": "token:/etc/luxel/token",
}


def hardening_problems(text):
    s = parse_unit(text)
    problems = []
    for key, want in REQUIRED.items():
        got = values(s, "Service", key)
        if not got or got[-1] != want:
            problems.append(f"{key}={want} expected, got {got}")
    if "@system-service" not in values(s, "Service", "SystemCallFilter"):
        problems.append("SystemCallFilter=@system-service missing")
    families = " ".join(values(s, "Service", "RestrictAddressFamilies")).split()
    if not families or set(families) - {"AF_UNIX", "AF_INET", "AF_INET6"}:
        problems.append(f"RestrictAddressFamilies too wide or missing: {families}")
    if values(s, "Service", "MemoryDenyWriteExecute") != ["yes"]:
        problems.append("MemoryDenyWriteExecute=yes expected (PoCL's JIT works under it: "
                        "tests/deploy/sandbox_test.py)")
    stop = values(s, "Service", "TimeoutStopSec")
    if not stop or not 30 <= int(stop[-1].rstrip("s")) <= 600:
        problems.append(f"TimeoutStopSec must leave time for a checkpoint: {stop}")
    exec_start = values(s, "Service", "ExecStart")
    if len(exec_start) != 1:
        problems.append(f"one ExecStart expected: {exec_start}")
    else:
        argv = exec_start[0].split()
        if "--token" in argv:
            problems.append("--token on the command line")
        if "--token-file" not in argv or argv[argv.index("--token-file") + 1] != "%d/token":
            problems.append("token not read from the credential (--token-file %d/token)")
        if "--data-dir" not in argv or not argv[argv.index("--data-dir") + 1].endswith("/luxel"):
            problems.append("--data-dir is not the StateDirectory")
    if "multi-user.target" not in values(s, "Install", "WantedBy"):
        problems.append("WantedBy=multi-user.target missing")
    return problems


def exec_binary(text):
    return values(parse_unit(text), "Service", "ExecStart")[0].split()[0]


class SystemdUnitTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with open(ARGS.unit) as f:
            cls.text = f.read()
        cls.tmp = tempfile.mkdtemp(prefix="luxeld-unit-")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_hardening_keys(self):
        self.assertEqual(hardening_problems(self.text), [])

    def test_hardening_check_rejects_a_weakened_unit(self):
        for old, new in [("ProtectSystem=strict", "ProtectSystem=full"),
                         ("CapabilityBoundingSet=\n", "CapabilityBoundingSet=CAP_NET_ADMIN\n"),
                         ("--token-file %d/token", "--token-file /etc/luxel/token"),
                         ("MemoryDenyWriteExecute=yes", "MemoryDenyWriteExecute=no")]:
            self.assertIn(old, self.text)
            self.assertNotEqual(hardening_problems(self.text.replace(old, new)), [], new)

    def _analyze(self, text, *args):
        """systemd-analyze on a copy whose ExecStart is the luxeld just built
        (verify checks that the binary exists)."""
        path = os.path.join(self.tmp, "luxeld.service")
        with open(path, "w") as f:
            f.write(text.replace(exec_binary(text), os.path.abspath(ARGS.luxeld), 1))
        return subprocess.run(["systemd-analyze", *args, path], capture_output=True,
                              text=True, timeout=60, cwd=self.tmp)

    @unittest.skipUnless(shutil.which("systemd-analyze"), "systemd-analyze not installed")
    def test_systemd_analyze_verify_is_silent(self):
        # verify exits 0 on unknown keys and bad values, with a warning: any
        # output is a failure.
        r = self._analyze(self.text, "verify")
        self.assertEqual((r.returncode, r.stdout + r.stderr), (0, ""))
        bad = self._analyze(self.text.replace("ProtectHome=yes", "ProtectHome=maybe"), "verify")
        self.assertIn("maybe", bad.stdout + bad.stderr)
        bad = self._analyze(self.text.replace("PrivateTmp=yes", "PrivateTemp=yes"), "verify")
        self.assertIn("Unknown key", bad.stdout + bad.stderr)

    @unittest.skipUnless(shutil.which("systemd-analyze"), "systemd-analyze not installed")
    def test_exposure_score_at_most_2(self):
        # systemd's own exposure score (0 = locked down, 10 = unprotected);
        # --threshold is in tenths. The unit scores 1.2 with systemd 252.
        r = self._analyze(self.text, "security", "--offline=yes", "--threshold=20")
        if "Unknown option" in r.stderr or "unrecognized option" in r.stderr:
            self.skipTest("systemd-analyze security --offline needs systemd >= 250")
        self.assertEqual(r.returncode, 0, r.stdout[-2000:] + r.stderr)
        weak = self.text.replace("ProtectSystem=strict", "ProtectSystem=no").replace(
            "CapabilityBoundingSet=\n", "").replace("DynamicUser=yes", "DynamicUser=no").replace(
            "SystemCallFilter=", "#").replace("PrivateDevices=yes", "PrivateDevices=no")
        r = self._analyze(weak, "security", "--offline=yes", "--threshold=20")
        self.assertNotEqual(r.returncode, 0, "a weakened unit must score worse than 2.0")

    def test_exec_start_is_where_cmake_installs_luxeld(self):
        # The unit assumes CMake's default prefix, /usr/local.
        prefix = os.path.join(self.tmp, "prefix")
        r = subprocess.run(["cmake", "--install", ARGS.build, "--prefix", prefix],
                           capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        binary = exec_binary(self.text)
        self.assertTrue(binary.startswith("/usr/local/"), binary)
        installed = os.path.join(prefix, os.path.relpath(binary, "/usr/local"))
        self.assertTrue(os.access(installed, os.X_OK), f"cmake --install made no {installed}")
        self.assertTrue(os.access(os.path.join(prefix, "bin", "luxel"), os.X_OK))
        unit = os.path.join(prefix, "lib", "systemd", "system", "luxeld.service")
        with open(unit) as f:
            self.assertEqual(f.read(), self.text)
        # deploy/container/Containerfile copies the guide from here.
        self.assertTrue(os.path.isfile(os.path.join(prefix, "share", "doc", "luxel", "operations.md")))
        out = subprocess.run([installed, "--help"], capture_output=True, text=True, timeout=30)
        self.assertIn("--data-dir", out.stdout)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--unit", required=True)
    p.add_argument("--luxeld", required=True)
    p.add_argument("--build", required=True)
    ARGS, rest = p.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
