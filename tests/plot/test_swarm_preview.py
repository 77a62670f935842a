"""Tests of swarm-preview (preview/main.cpp): a scenario flown by the bare laws in lockstep, its
report, its CSV (what `swarm paper` draws its lockstep numbers from) and its exit codes.

Usage: test_swarm_preview.py BUILD_BIN_DIR   (ctest -L plot runs it)
"""

import csv
import os
import subprocess
import sys
import tempfile
import unittest

BIN = None
SOURCE = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
UNWEIGHTED = os.path.join(SOURCE, "scenarios", "paper", "unweighted.txtpb")
INSIDER = os.path.join(SOURCE, "scenarios", "insider_seven.txtpb")


def preview(*args, cwd=None):
    return subprocess.run([os.path.join(BIN, "swarm-preview"), *args], capture_output=True,
                          text=True, timeout=120, cwd=cwd)


def read_csv(path):
    with open(path, encoding="utf-8") as f:
        return list(csv.DictReader(f))


class SwarmPreviewTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="swarm-preview-test-")
        cls.root = cls.tmp.name

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def scenario(self, name, text):
        path = os.path.join(self.root, name)
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        return path

    def test_without_a_scenario_it_flies_the_demo_to_the_papers_point(self):
        # From the repository root it reads scenarios/demo.txtpb; from anywhere else, the build
        # tree's copy.
        for cwd in (SOURCE, self.root):
            r = preview(cwd=cwd)
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
            self.assertIn("demo: Paper 2.7.2", r.stdout)
            self.assertIn("edge-flow law, 50 Hz", r.stdout)  # the demo's law and default rate
            self.assertIn("met after", r.stdout)
            self.assertIn("paper q*  (15.250000, 10.250000, 31.000000)", r.stdout)

    def test_a_scenario_is_compared_with_its_initial_average(self):
        r = preview(UNWEIGHTED)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("paper_unweighted", r.stdout)
        self.assertIn("initial average (10.250000, 9.750000, 29.250000)", r.stdout)
        self.assertIn("tolerance 0.005 m", r.stdout)  # the scenario's convergence.tolerance_m

    def test_csv_has_every_agent_at_every_tick_and_is_byte_stable(self):
        a, b = os.path.join(self.root, "a.csv"), os.path.join(self.root, "b.csv")
        for path in (a, b):
            r = preview(UNWEIGHTED, "--law", "laplacian", "--duration", "2", "--csv", path)
            self.assertEqual(r.returncode, 0, r.stderr)
        with open(a, "rb") as fa, open(b, "rb") as fb:
            self.assertEqual(fa.read(), fb.read())
        rows = read_csv(a)
        self.assertEqual(list(rows[0]), ["t_s", "id", "qx", "qy", "qz"])
        ticks = sorted({float(row["t_s"]) for row in rows})
        self.assertEqual(len(rows), 4 * len(ticks))
        self.assertEqual(ticks[0], 0.0)
        self.assertAlmostEqual(ticks[1], 0.02, delta=1e-12)  # the scenario's 50 Hz (the default)
        self.assertLess(ticks[-1], 2.0 + 0.02 + 1e-9)  # --duration 2 overrides the scenario's 60
        self.assertEqual([row["id"] for row in rows[:4]], ["1", "2", "3", "4"])
        self.assertEqual([float(rows[0][c]) for c in ("qx", "qy", "qz")], [4, 17, 24])

    def test_laplacian_and_edge_flow_coincide_in_lockstep(self):
        # What lets `swarm paper` compare the edge-flow swarm with the lockstep laplacian law.
        out = {}
        for law in ("laplacian", "edge-flow"):
            out[law] = os.path.join(self.root, f"{law}.csv")
            r = preview(UNWEIGHTED, "--law", law, "--csv", out[law])
            self.assertEqual(r.returncode, 0, r.stderr)
        lap, edge = read_csv(out["laplacian"]), read_csv(out["edge-flow"])
        self.assertEqual(len(lap), len(edge))
        for x, y in zip(lap, edge):
            for c in ("qx", "qy", "qz"):
                self.assertAlmostEqual(float(x[c]), float(y[c]), delta=1e-12)

    def test_bad_input_is_named_and_exits_2(self):
        bad_gain = self.scenario("bad_gain.txtpb", 'name: "g"\nagents { id: 1 }\n'
                                 "agents { id: 2 position { x: 2 } }\ngain: -1\n")
        radio = self.scenario("radio.txtpb", 'name: "r"\nagents { id: 1 }\n'
                              "agents { id: 2 position { x: 2 } }\n"
                              "topology { policy: RANGE threshold_m: 5 }\n")
        for args, named in ((["--law", "fast"], "--law"), (["--duration", "0"], "--duration"),
                            (["--duration", "5x"], "--duration"), (["--rate", "50"], "--rate"),
                            ([bad_gain], "gain"), ([radio], "topology.policy"),
                            ([os.path.join(self.root, "none.txtpb")], "none.txtpb"),
                            (["--csv", os.path.join(self.root, "no", "dir.csv")], "--csv")):
            r = preview(*args)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn(named, r.stderr, args)
            self.assertEqual(r.stderr.count("\n"), 1, r.stderr)

    def test_w_msr_keeps_the_honest_agents_in_their_box_under_a_liar(self):
        path = os.path.join(self.root, "liar.csv")
        r = preview(INSIDER, "--liar", "7:split", "--duration", "60", "--csv", path)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("agent 7 lied (split) for 60.00 s", r.stdout)
        self.assertIn("the honest agents met inside their initial bounding box", r.stdout)
        rows = read_csv(path)
        self.assertEqual(sorted({row["id"] for row in rows}), ["1", "2", "3", "4", "5", "6"])
        self.assertAlmostEqual(max(float(row["t_s"]) for row in rows), 60.0, delta=0.02 + 1e-9)

    def test_a_law_that_trusts_everyone_is_dragged_and_exits_1(self):
        r = preview(INSIDER, "--law", "laplacian", "--liar", "7:constant:-500,0,0",
                    "--duration", "30")
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("dragged them out of their initial bounding box", r.stdout)

    def test_a_bad_liar_is_named_and_exits_2(self):
        for value in ("7", "7:lies", "0:constant", "x:drift", "9:constant", "7:drift:1,2",
                      "7:constant:1,2,nan", "7:split:1,2,3,4", "-1:constant"):
            r = preview(INSIDER, "--liar", value)
            self.assertEqual(r.returncode, 2, value)
            self.assertIn("--liar", r.stderr, value)
            self.assertEqual(r.stderr.count("\n"), 1, r.stderr)

    def test_a_csv_that_cannot_be_written_completely_exits_3(self):
        if not os.path.exists("/dev/full"):
            self.skipTest("no /dev/full")
        r = preview(UNWEIGHTED, "--csv", "/dev/full")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("/dev/full", r.stderr)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print("usage: test_swarm_preview.py BUILD_BIN_DIR", file=sys.stderr)
        sys.exit(2)
    BIN = os.path.abspath(sys.argv.pop(1))
    unittest.main(verbosity=2)
