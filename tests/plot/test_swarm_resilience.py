"""Tests of `swarm resilience` (python/qswarm/resilience.py driving swarm-preview --liar): the
three laws under one insider's attacks, end to end; its numbers are the core test's
(tests/core/insider_seven_expected.csv, which InsiderTable.* holds the C++ laws to) and its table
is the one in docs/resilience.md.

Usage: test_swarm_resilience.py BUILD_BIN_DIR   (ctest -L plot runs it)
"""

import csv
import os
import subprocess
import sys
import tempfile
import unittest

BIN = None
SOURCE = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
EXPECTED = os.path.join(SOURCE, "tests", "core", "insider_seven_expected.csv")
DOC = os.path.join(SOURCE, "docs", "resilience.md")
NUMERIC = ["outside_m", "max_outside_m", "disagreement_m", "mean_x", "mean_y", "mean_z"]


def swarm(*args, cwd=SOURCE):
    return subprocess.run([os.path.join(BIN, "swarm"), *args], capture_output=True, text=True,
                          timeout=600, cwd=cwd)


def read_csv(path):
    with open(path, encoding="utf-8") as f:
        return list(csv.DictReader(f))


class SwarmResilienceTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="swarm-resilience-test-")
        cls.out = os.path.join(cls.tmp.name, "a")
        # With the defaults (scenarios/insider_seven.txtpb, agent 7), from outside the repository:
        # the defaults are the source tree's wherever the command runs.
        cls.first = swarm("resilience", "--out", cls.out, cwd=cls.tmp.name)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_it_writes_the_figure_and_the_numbers(self):
        self.assertEqual(self.first.returncode, 0, self.first.stdout + self.first.stderr)
        with open(os.path.join(self.out, "insider.png"), "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertIn(os.path.join(self.out, "numbers.csv"), self.first.stdout)

    def test_its_numbers_are_the_core_tests(self):
        self.assertEqual(self.first.returncode, 0, self.first.stderr)
        got = read_csv(os.path.join(self.out, "numbers.csv"))
        want = read_csv(EXPECTED)
        self.assertEqual([(r["law"], r["attack"]) for r in got],
                         [(r["law"], r["attack"]) for r in want])
        for g, w in zip(got, want):
            for c in NUMERIC:
                with self.subTest(law=w["law"], attack=w["attack"], column=c):
                    self.assertAlmostEqual(float(g[c]), float(w[c]),
                                           delta=1e-9 + 1e-9 * abs(float(w[c])))
        # What the numbers say: W-MSR's honest agents stay in their box and agree; the others
        # are dragged at least 100 m out.
        for r in got:
            if r["law"] == "w-msr":
                self.assertEqual(float(r["max_outside_m"]), 0.0, r)
                self.assertLess(float(r["disagreement_m"]), 1e-9, r)
            else:
                self.assertGreater(float(r["outside_m"]), 100.0, r)

    def test_the_table_it_prints_is_the_one_in_the_docs(self):
        self.assertEqual(self.first.returncode, 0, self.first.stderr)
        with open(DOC, encoding="utf-8") as f:
            doc = f.read()
        rows = [line for line in self.first.stdout.splitlines() if line.startswith("|")]
        self.assertEqual(len(rows), 2 + 9)
        for line in rows:
            self.assertIn(line + "\n", doc)

    def test_the_same_scenario_gives_the_same_bytes(self):
        self.assertEqual(self.first.returncode, 0, self.first.stderr)
        again = os.path.join(self.tmp.name, "b")
        r = swarm("resilience", os.path.join(SOURCE, "scenarios", "insider_seven.txtpb"),
                  "--out", again, "--liar", "7", cwd=self.tmp.name)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.replace(again, self.out), self.first.stdout)
        for name in ("insider.png", "numbers.csv"):
            with open(os.path.join(self.out, name), "rb") as fa, \
                    open(os.path.join(again, name), "rb") as fb:
                self.assertEqual(fa.read(), fb.read(), name)

    def test_bad_input_is_named_and_exits_2(self):
        r = swarm("resilience", "--out", os.path.join(self.tmp.name, "c"), "--liar", "9")
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertIn("--liar: agent 9", r.stderr)
        r = swarm("resilience", os.path.join(self.tmp.name, "none.txtpb"))
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertIn("none.txtpb", r.stderr)

    def test_a_directory_that_cannot_be_written_exits_3(self):
        blocker = os.path.join(self.tmp.name, "file")
        with open(blocker, "w", encoding="utf-8") as f:
            f.write("not a directory\n")
        r = swarm("resilience", "--out", os.path.join(blocker, "out"))
        self.assertEqual(r.returncode, 3, r.stdout + r.stderr)
        self.assertIn("file", r.stderr)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print("usage: test_swarm_resilience.py BUILD_BIN_DIR", file=sys.stderr)
        sys.exit(2)
    BIN = os.path.abspath(sys.argv.pop(1))
    unittest.main(verbosity=2)
