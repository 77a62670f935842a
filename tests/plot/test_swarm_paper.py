#!/usr/bin/python3
"""Tests of `swarm paper` (launcher/main.cpp + python/qswarm/paper.py), end to end.

Flies the paper's scenarios once with the real multi-process swarm (about a minute of wall time
here) into a temporary directory on a leased DDS test domain, then checks what a user relies on:
every figure and the report are written, the report's numbers are the paper's where they should be,
drawing the same runs again gives identical bytes, and bad or failed runs give no report.

Usage: test_swarm_paper.py BUILD_BIN_DIR   (ctest -L paper runs it)
"""

import fcntl
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
import zlib

BIN = None
FIGURES = [
    "fig01_unweighted_l2_3d.png", "fig02_unweighted_l2_agent1_xyz.png", "fig03_weighted_3d.png",
    "fig04_weighted_agent1_xyz.png", "fig05_time_varying_3d.png",
    "fig06_time_varying_agent1_xyz.png", "fig07_maneuver_path_and_attitude.png",
    "fig08_maneuver_controls.png", "fig09_rendezvous3_paths.png", "fig10_rendezvous3_yaw.png",
    "fig11_rendezvous3_controls.png", "fig12_rendezvous3_with_without_dynamics.png",
    "swarm_quadcopters_3d.png",
]
RUN_NAMES = ["unweighted", "unweighted_l2", "weighted_baseline", "weighted",
             "time_varying_baseline", "time_varying", "rendezvous3", "time_varying_quadcopter"]
PAPER_POINTS = {"unweighted": (10.25, 9.75, 29.25), "unweighted_l2": (10.25, 9.75, 29.25),
                "weighted_baseline": (9, 12.75, 30.25), "weighted": (9, 12.75, 30.25),
                "time_varying_baseline": (15.25, 10.25, 31), "time_varying": (15.25, 10.25, 31),
                "rendezvous3": (5, 6, 0), "time_varying_quadcopter": (15.25, 10.25, 31)}
# The eigenvalues of each run's initial Laplacian (tests/core holds them against the paper's
# matrices): 2.6.1's L_1 and L_2, 2.7.1's distance weights, 2.7.2's printed L_2i, K_3.
EIGENVALUES = {"unweighted": (0, 1, 3, 4), "unweighted_l2": (0, 0.586, 2, 3.414),
               "weighted": (0, 13.060, 42.248, 62.558), "time_varying": (0, 6.240, 19.385, 37.655),
               "time_varying_baseline": (0, 0.586, 2, 3.414), "rendezvous3": (0, 3, 3)}


def lease_domain(key):
    """A DDS domain in 10..22 no other test holds (tests/swarm/domain_lease's flock scheme)."""
    os.makedirs("/tmp/qswarm-test-domains", exist_ok=True)
    start = zlib.crc32(key.encode()) % 13
    for k in range(13):
        d = 10 + (start + k) % 13
        f = open(f"/tmp/qswarm-test-domains/{d}.lock", "a+")
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return d, f
        except OSError:
            f.close()
    raise RuntimeError("no free DDS test domain")


def swarm(*args):
    return subprocess.run([os.path.join(BIN, "swarm"), *args], capture_output=True, text=True,
                          timeout=900)


def tree(d):
    out = {}
    for name in sorted(os.listdir(d)):
        with open(os.path.join(d, name), "rb") as f:
            out[name] = f.read()
    return out


class SwarmPaperTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="swarm-paper-test-")
        cls.root = cls.tmp.name
        cls.domain, cls.lock = lease_domain("SwarmPaperTest")
        cls.runs = os.path.join(cls.root, "runs")
        cls.out = os.path.join(cls.root, "out")
        cls.first = swarm("paper", "--runs", cls.runs, "--out", cls.out, "--domain",
                          str(cls.domain), "--scenarios",
                          os.path.join(SOURCE, "scenarios", "paper"))

    @classmethod
    def tearDownClass(cls):
        cls.lock.close()
        cls.tmp.cleanup()

    def copy_runs(self, name):
        dst = os.path.join(self.root, name)
        shutil.copytree(self.runs, dst)
        return dst

    def paper_from(self, runs, out):
        return swarm("paper", "--from", runs, "--out", out, "--scenarios",
                     os.path.join(SOURCE, "scenarios", "paper"))

    def test_flies_every_run_and_writes_every_figure_and_the_report(self):
        r = self.first
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        for name in RUN_NAMES:
            summary = os.path.join(self.runs, name, run_dir_names.SUMMARY)
            self.assertTrue(os.path.isfile(summary), name)
        maneuvers = os.path.join(self.runs, run_dir_names.MANEUVERS)
        for name in (run_dir_names.SINGLE_AGENT, run_dir_names.RENDEZVOUS_DYNAMICS,
                     run_dir_names.SEGMENTS):
            self.assertTrue(os.path.isfile(os.path.join(maneuvers, name)), name)
        listed = r.stdout.split()
        for name in FIGURES + ["report.md"]:
            path = os.path.join(self.out, name)
            self.assertIn(path, listed)
            self.assertGreater(os.path.getsize(path), 1000, name)
        for name in FIGURES:
            with open(os.path.join(self.out, name), "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n", name)
        self.assertEqual(sorted(os.listdir(self.out)), sorted(FIGURES + ["report.md"]))

    def test_report_puts_our_numbers_beside_the_papers(self):
        with open(os.path.join(self.out, "report.md"), encoding="utf-8") as f:
            text = f.read()
        for name in FIGURES:
            self.assertIn(f"]({name})", text)
        rows = {}
        for stem in PAPER_POINTS:
            row = next(line for line in text.splitlines() if line.startswith(f"| `{stem}` |"))
            rows[stem] = [c.strip() for c in row.split("|")]
        # Every run's agreed point (measured) within 1e-3 m of the paper's.
        for stem, q in PAPER_POINTS.items():
            ours = [float(x) for x in rows[stem][3].strip("()").split(",")]
            for a, b in zip(ours, q):
                self.assertAlmostEqual(a, b, delta=1e-3, msg=stem)
        # Our eigenvalues (from each run's own scenario.txtpb) are the initial Laplacians'.
        for stem, eig in EIGENVALUES.items():
            ours = [float(x) for x in rows[stem][6].strip("{}").split(",")]
            self.assertEqual(len(ours), len(eig), stem)
            for a, b in zip(ours, eig):
                self.assertAlmostEqual(a, b, delta=1e-3, msg=stem)
        # Measured decay rates of the fixed graphs are near lambda_2, and so is each one's lockstep
        # rate (the same law without DDS, from swarm-preview): within 5 % unweighted, within 10 %
        # weighted, whose fast modes a 50 Hz tick slows (a tick moves an edge by
        # (w/W)(1 - exp(-k W dt)), short of k w dt: 12.18 against 13.06 here).
        for stem, lam, tol in (("unweighted", 1.0, 0.05), ("unweighted_l2", 0.586, 0.05),
                               ("rendezvous3", 3.0, 0.05), ("weighted", 13.06, 0.10)):
            measured, lock = (float(x) for x in rows[stem][7].split("/"))
            self.assertAlmostEqual(lock, lam, delta=tol * lam, msg=stem)
            self.assertGreater(measured, 0.5 * lam, stem)
        # The weighted network converges faster, by a ratio of decay rates near lambda_2's 13.06.
        m = re.search(r"measured decay rates ([0-9.]+) against ([0-9.]+)", text)
        self.assertIsNotNone(m)
        self.assertGreater(float(m.group(1)) / float(m.group(2)), 8.0)
        # The quadcopters agree on the paper's point but, with collision avoidance, hold in a
        # cluster about it, never closer than the safe distance; the report says so from the run.
        with open(os.path.join(self.runs, "time_varying_quadcopter", run_dir_names.SUMMARY),
                  encoding="utf-8") as f:
            quad = json.load(f)
        self.assertTrue(quad["avoidance"])
        self.assertGreaterEqual(quad["min_separation_m"], quad["safe_distance_m"])
        self.assertEqual(quad.get("separation_violations", 0), 0)
        m = re.search(r"hold in a cluster about it, ([0-9., ]+) m from it. The closest pair over "
                      r"the run was ([0-9.]+) m apart, with 0 violations", text)
        self.assertIsNotNone(m)
        self.assertEqual(len(m.group(1).split(",")), 4)
        self.assertAlmostEqual(float(m.group(2)), quad["min_separation_m"], delta=0.006)
        self.assertIsNone(re.search(r"\bnan\b", text, re.I))  # every number was measured

    def test_drawing_the_same_runs_again_gives_identical_bytes(self):
        out2 = os.path.join(self.root, "out-again")
        r = self.paper_from(self.runs, out2)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(tree(self.out), tree(out2))

    def test_a_missing_maneuver_file_is_named_and_exits_2(self):
        runs = self.copy_runs("runs-no-maneuver")
        os.remove(os.path.join(runs, run_dir_names.MANEUVERS, run_dir_names.SINGLE_AGENT))
        out = os.path.join(self.root, "out-no-maneuver")
        r = self.paper_from(runs, out)
        self.assertEqual(r.returncode, 2)
        self.assertIn(run_dir_names.SINGLE_AGENT, r.stderr)
        self.assertFalse(os.path.exists(os.path.join(out, "report.md")))

    def test_a_half_written_run_is_named_and_exits_2(self):
        runs = self.copy_runs("runs-half")
        path = os.path.join(runs, "weighted", run_dir_names.SUMMARY)
        with open(path, "r+", encoding="utf-8") as f:
            text = f.read()
            f.seek(0)
            f.truncate()
            f.write(text[: len(text) // 2])
        r = self.paper_from(runs, os.path.join(self.root, "out-half"))
        self.assertEqual(r.returncode, 2)
        self.assertIn(os.path.join("weighted", run_dir_names.SUMMARY), r.stderr)

    def test_a_run_that_did_not_converge_gives_no_report(self):
        runs = self.copy_runs("runs-failed")
        path = os.path.join(runs, "time_varying", run_dir_names.SUMMARY)
        with open(path, encoding="utf-8") as f:
            text = f.read()
        with open(path, "w", encoding="utf-8") as f:
            f.write(text.replace('"converged": true', '"converged": false', 1))
        out = os.path.join(self.root, "out-failed")
        os.makedirs(out)
        with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
            f.write("the previous report\n")
        r = self.paper_from(runs, out)
        self.assertEqual(r.returncode, 1)
        self.assertIn("time_varying", r.stderr)
        self.assertIn("did not converge", r.stderr)
        with open(os.path.join(out, "report.md"), encoding="utf-8") as f:
            self.assertEqual(f.read(), "the previous report\n")  # left as it was
        self.assertEqual(os.listdir(out), ["report.md"])

    def test_an_output_that_cannot_be_written_exits_3(self):
        blocker = os.path.join(self.root, "a-file")
        with open(blocker, "w", encoding="utf-8") as f:
            f.write("not a directory\n")
        r = self.paper_from(self.runs, blocker)
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn(blocker, r.stderr)

    def test_runs_that_hold_files_are_refused_naming_runs(self):
        r = swarm("paper", "--runs", self.runs, "--out", os.path.join(self.root, "never-runs"),
                  "--scenarios", os.path.join(SOURCE, "scenarios", "paper"))
        self.assertEqual(r.returncode, 2)
        self.assertIn("--runs", r.stderr)
        self.assertNotIn("--out", r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.root, "never-runs")))

    def test_bad_flags_name_the_flag_and_exit_2(self):
        for args, flag in ((["--time-scale", "nan"], "--time-scale"),
                           (["--time-scale", "0"], "--time-scale"),
                           (["--domain", "999"], "--domain"),
                           (["--from", os.path.join(self.root, "nowhere")], "--from"),
                           (["--from", self.runs, "--runs", self.runs], "--runs"),
                           (["--from", self.runs, "--time-scale", "2"], "--time-scale")):
            r = swarm("paper", *args, "--out", os.path.join(self.root, "never"))
            self.assertEqual(r.returncode, 2, args)
            self.assertIn(flag, r.stderr + r.stdout, args)
        self.assertFalse(os.path.exists(os.path.join(self.root, "never")))


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print("usage: test_swarm_paper.py BUILD_BIN_DIR", file=sys.stderr)
        sys.exit(2)
    BIN = os.path.abspath(sys.argv.pop(1))
    sys.path.insert(0, os.path.join(BIN, "python"))  # the build's copy of python/qswarm
    from qswarm import run_dir as run_dir_names
    SOURCE = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    unittest.main()
