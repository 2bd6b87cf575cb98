"""Does PoCL's kernel JIT run under systemd's MemoryDenyWriteExecute=yes?

mdwe_exec (mdwe_exec.c) installs the seccomp rules systemd 252 uses for the
option. First a control: a W+X mapping must fail under it (else the filter
proves nothing). Then `luxel inspect` traces rays on PoCL with an empty
POCL_CACHE_DIR, so PoCL compiles, writes and loads kernel code under the
filter; it must succeed and PoCL's cache must have filled. This decides
MemoryDenyWriteExecute= in deploy/systemd/luxeld.service.

usage: pocl_mdwe_test.py --mdwe-exec BIN --luxel BIN --scene GLTF --unit FILE
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

ARGS = None


class PoclUnderMdwe(unittest.TestCase):
    def test_filter_refuses_writable_executable_memory(self):
        code = "import mmap; mmap.mmap(-1, 4096, prot=mmap.PROT_READ | mmap.PROT_WRITE | mmap.PROT_EXEC)"
        free = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=30)
        self.assertEqual(free.returncode, 0, free.stderr)
        r = subprocess.run([ARGS.mdwe_exec, sys.executable, "-c", code], capture_output=True,
                           text=True, timeout=30)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("PermissionError", r.stderr)

    def test_pocl_jit_runs_under_the_filter(self):
        pocl_cache = tempfile.mkdtemp(prefix="pocl-mdwe-")
        try:
            env = dict(os.environ, POCL_CACHE_DIR=pocl_cache)
            r = subprocess.run([ARGS.mdwe_exec, ARGS.luxel, "inspect", ARGS.scene, "--rays", "10000",
                                "--device", "cpu"],
                               capture_output=True, text=True, timeout=120, env=env)
            self.assertEqual(r.returncode, 0, r.stdout[-2000:] + r.stderr[-2000:])
            self.assertIn("intersect_closest", r.stdout)
            jitted = [f for _, _, fs in os.walk(pocl_cache) for f in fs]
            self.assertTrue(jitted, "PoCL compiled nothing: the test did not exercise its JIT")
        finally:
            shutil.rmtree(pocl_cache, ignore_errors=True)

    def test_unit_sets_memory_deny_write_execute(self):
        with open(ARGS.unit) as f:
            lines = [l.strip() for l in f]
        self.assertIn("MemoryDenyWriteExecute=yes", lines)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--mdwe-exec", required=True)
    p.add_argument("--luxel", required=True)
    p.add_argument("--scene", required=True)
    p.add_argument("--unit", required=True)
    ARGS, rest = p.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
