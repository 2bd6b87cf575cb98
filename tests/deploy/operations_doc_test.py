"""docs/operations.md documents every flag `luxeld --help` prints (so a new
flag cannot ship undocumented for operators), and every deploy/ file it
points at exists.

usage: operations_doc_test.py --luxeld BIN
"""
import argparse
import os
import re
import subprocess
import sys
import unittest

ARGS = None
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DOC = os.path.join(ROOT, "docs", "operations.md")


def help_flags(help_text):
    return set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]+)", help_text))


def undocumented(help_text, doc):
    documented = set(re.findall(r"`(--[a-z][a-z0-9-]+)", doc))
    return sorted(help_flags(help_text) - documented)


class OperationsDoc(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        r = subprocess.run([ARGS.luxeld, "--help"], capture_output=True, text=True, timeout=30)
        assert r.returncode == 0, r.stderr
        cls.help = r.stdout
        with open(DOC) as f:
            cls.doc = f.read()

    def test_every_flag_documented(self):
        self.assertGreaterEqual(len(help_flags(self.help)), 10)
        self.assertEqual(undocumented(self.help, self.doc), [])

    def test_a_new_flag_would_be_caught(self):
        self.assertEqual(undocumented(self.help + "  --frobnicate N  new\n", self.doc),
                         ["--frobnicate"])

    def test_deploy_paths_exist(self):
        paths = set(re.findall(r"`((?:deploy|docs|tests)/[\w./-]+)`", self.doc))
        self.assertGreater(len(paths), 5)
        for p in sorted(paths):
            self.assertTrue(os.path.exists(os.path.join(ROOT, p)), p)

    def test_linked_from_readme_and_architecture(self):
        for name in ("README.md", os.path.join("docs", "architecture.md")):
            with open(os.path.join(ROOT, name)) as f:
                self.assertTrue("operations.md" in f.read(), f"{name} does not link operations.md")


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--luxeld", required=True)
    ARGS, rest = p.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
