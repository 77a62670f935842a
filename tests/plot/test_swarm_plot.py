#!/usr/bin/python3
"""Tests of `swarm plot` (launcher/main.cpp + python/qswarm/plot.py) on synthetic run directories.

The run directories are written by make_run() below in the recorder's exact formats
(common/record/): telemetry.csv and graph.csv with 10 significant digits, edge weights and
events.csv times with 6, quoted edge lists and event details, and a summary.json as protobuf's JSON
printer writes it.

Usage: test_swarm_plot.py BUILD_BIN_DIR   (ctest -L plot runs it)
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np

BIN = None

TELEMETRY_HEADER = ("stamp_s,id,seq,phase,mode,qx,qy,qz,px,py,pz,vx,vy,vz,qw,qxr,qyr,qzr,w1,w2,w3,"
                    "w4,total_weight,links,age_ms")
GRAPH_HEADER = ("t_s,agents,edges,lambda2,components,disagreement_m,mean_drift_m,"
                "min_separation_m,spread_m,edge_list")
COMMON = ["trajectories_3d.png", "positions.png", "graph.png", "graph_snapshots.png",
          "disagreement.png"]
QUAD = ["attitude.png", "rotors.png", "thrust.png"]

K_R = 2.9842e-5
HOVER = math.sqrt(0.468 * 9.81 / (4 * K_R))


def g(x, digits=10):
    """What a C++ ostream with setprecision(digits) writes for a double."""
    return f"{x:.{digits}g}"


def components_and_lambda2(ids, edges):
    n = len(ids)
    if n == 0:
        return 0, 0.0
    k = {a: i for i, a in enumerate(ids)}
    lap = np.zeros((n, n))
    for a, b, w in edges:
        i, j = k[a], k[b]
        lap[i, j] -= w
        lap[j, i] -= w
        lap[i, i] += w
        lap[j, j] += w
    ev = np.linalg.eigvalsh(lap)
    comps = int(np.sum(ev < 1e-9))
    return comps, float(ev[1]) if n > 1 else 0.0


def make_run(root, name, n_agents=4, duration=4.0, quad=False, seed=7, rate_hz=50.0,
             faults=True, proximity_m=None):
    """Writes a synthetic run directory mimicking the recorder; returns its path.

    Agents move exponentially to the average of their start positions. With faults: link 1-2 is
    cut from 0.5 s to 1.2 s and agent 3 is killed at 1.5 s and restarted at 2.5 s (no samples from
    it in between). Waiting samples precede the run and stopping samples end it, as in a real run.
    """
    rng = np.random.default_rng(seed)
    d = os.path.join(root, name)
    os.makedirs(d)
    ids = list(range(1, n_agents + 1))
    p0 = rng.uniform([0, 0, 20], [20, 20, 35], size=(n_agents, 3))
    yaw0 = rng.uniform(-math.pi, math.pi, size=n_agents)
    avg = p0.mean(axis=0)
    cut = (0.5, 1.2, 1, 2) if faults else None
    mode = 1 if quad else 0
    kill = (1.5, 2.5, 3) if faults and n_agents >= 3 else None

    def q_at(t):
        return avg + (p0 - avg) * math.exp(-1.5 * t)

    def q_of(t, k):  # rows of times t for agents (indices) k
        return avg + (p0[k] - avg) * np.exp(-1.5 * np.maximum(t, 0.0))[:, None]

    def alive(aid, t):
        return not (kill and aid == kill[2] and kill[0] <= t < kill[1])

    # telemetry.csv: waiting and ready samples, the running ones every 1/rate_hz, stopping ones
    times = np.arange(int(round(duration * rate_hz)) + 1) / rate_hz
    n_steps = len(times) - 1
    tt = np.repeat(times, n_agents)
    kk = np.tile(np.arange(n_agents), len(times))
    keep = np.array([alive(ids[k], t) for t, k in zip(tt, kk)]) if kill else np.ones(tt.size, bool)
    tt, kk = tt[keep], kk[keep]
    t_all = np.concatenate([np.zeros(2 * n_agents), tt, np.full(n_agents, duration)])
    k_all = np.concatenate([np.repeat(np.arange(n_agents), 2), kk, np.arange(n_agents)])
    phase = np.concatenate([np.tile([0, 3], n_agents), np.ones(tt.size), np.full(n_agents, 2)])
    seq = np.zeros(t_all.size)
    for k in range(n_agents):
        m = k_all == k
        seq[m] = np.arange(1, m.sum() + 1)
    q = q_of(t_all, k_all)
    if quad:
        p = q_of(np.maximum(t_all - 0.3, 0.0), k_all)
        v = -1.5 * (p - avg)
        yaw = yaw0[k_all] * np.exp(-t_all)
        roll, pitch = 0.05 * np.sin(3 * t_all + k_all), 0.04 * np.cos(2 * t_all + k_all)
        cr, sr = np.cos(roll / 2), np.sin(roll / 2)
        cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
        cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
        quat = np.column_stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                                cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])
        w = (HOVER + 5 * np.sin(4 * t_all[:, None] + np.arange(4) + k_all[:, None])
             + rng.normal(0, 0.5, (t_all.size, 4)))
    else:
        p, v = q, np.zeros_like(q)
        quat = np.tile([1.0, 0.0, 0.0, 0.0], (t_all.size, 1))
        w = np.zeros((t_all.size, 4))
    table = np.column_stack([t_all, np.array(ids)[k_all], seq, phase, np.full(t_all.size, mode),
                             q, p, v, quat, w, np.full(t_all.size, 3.5),
                             np.full(t_all.size, n_agents - 1),
                             np.abs(rng.normal(0.2, 0.05, t_all.size))])
    with open(os.path.join(d, run_dir_names.TELEMETRY), "w") as f:
        f.write(TELEMETRY_HEADER + "\n")
        np.savetxt(f, table, fmt="%.10g", delimiter=",")  # %.10g = ostream setprecision(10)

    # graph.csv: the initial graph at t 0, then every 0.1 s
    ia, ib = np.triu_indices(n_agents, 1)
    grows = []
    for s in range(int(round(duration * 10)) + 1):
        t = s / 10.0
        q = q_at(t)
        present = np.array([alive(a, t) for a in ids])
        dist = np.linalg.norm(q[ia] - q[ib], axis=1)
        on = present[ia] & present[ib]
        if cut and cut[0] <= t < cut[1]:
            on &= ~(((ia == cut[2] - 1) & (ib == cut[3] - 1)))
        if proximity_m and t > 0:
            on &= dist <= proximity_m
        weights = dist if proximity_m else np.ones_like(dist)
        edges = [(ia[e] + 1, ib[e] + 1, weights[e]) for e in np.nonzero(on)[0]]
        live = [a for a, ok in zip(ids, present) if ok]
        comps, l2 = components_and_lambda2(live, edges)
        qp = q[present]
        mean = qp.mean(axis=0)
        dis = float(np.max(np.linalg.norm(qp - mean, axis=1)))
        drift = float(np.linalg.norm(mean - avg))
        sep = float(dist[present[ia] & present[ib]].min())
        elist = ";".join(f"{a}-{b}:{w:.6g}" for a, b, w in edges)
        grows.append(",".join([g(t), str(len(live)), str(len(edges)), g(l2), str(comps),
                               g(dis), g(drift), g(sep), g(dis)]) + f',"{elist}"')
    with open(os.path.join(d, run_dir_names.GRAPH), "w") as f:
        f.write(GRAPH_HEADER + "\n" + "\n".join(grows) + "\n")

    # events.csv (times with the stream's default 6 significant digits, details quoted)
    ev = [(0, "join", a, "first sample") for a in ids]
    if cut:
        ev += [(cut[0], "cut", 1, "link 1-2 cut"), (cut[1], "cut_end", 1, "link 1-2 restored")]
    if kill:
        ev += [(kill[0], "kill", 3, "SIGKILL"), (kill[0] + 1.0, "depart", 3,
                                                 "silent past the neighbour timeout"),
               (kill[1], "restart", 3, "restarted"), (kill[1] + 0.02, "rejoin", 3,
                                                      "heard again after departure")]
    ev += [(duration * 0.9, "converged", 0, "disagreement 0.00412 m, spread 0.00412 m"),
           (duration, "end", 0, "converged")]
    ev.sort(key=lambda e: e[0])
    with open(os.path.join(d, run_dir_names.EVENTS), "w") as f:
        f.write("t_s,kind,agent,detail\n")
        for t, kind, a, det in ev:
            f.write(f'{g(t, 6)},{kind},{a},"{det}"\n')

    # summary.json (protobuf JSON, preserve_proto_field_names, always_print_primitive_fields)
    qf = q_at(duration)
    summary = {
        "scenario": name, "converged": True, "convergence_time_s": duration * 0.9 - 0.5,
        "agents": [{"id": a, "initial_position": list(map(float, p0[a - 1])),
                    "final_position": list(map(float, qf[a - 1])),
                    "final_consensus": list(map(float, qf[a - 1])), "samples": n_steps,
                    "seq_gaps": 0, "dropped_by_agent": 0, "rate_hz": rate_hz} for a in ids],
        "initial_average": list(map(float, avg)),
        "final_consensus_mean": list(map(float, qf.mean(0))),
        "max_final_spread_m": 0.004, "average_drift_m": 1e-12, "lambda2_initial": 4.0,
        "lambda2_final": 4.0, "edges_initial": [], "edges_final": [],
        "messages": {"published": 800, "received": 800}, "seed": seed,
        "mode": "quadcopter" if quad else "particle", "law": "edge_flow",
        "duration_s": duration, "agents_expected": n_agents, "joins": n_agents, "departures": 0,
        "min_separation_m": 0.1, "end_reason": "converged", "wall_time_s": duration,
        "final_disagreement_m": 0.004,
    }
    with open(os.path.join(d, run_dir_names.SUMMARY), "w") as f:
        json.dump(summary, f, indent=1)
    with open(os.path.join(d, run_dir_names.SCENARIO), "w") as f:
        f.write(f'name: "{name}"\n')
        for k, a in enumerate(ids):
            f.write(f"agents {{ id: {a} position {{ x: {p0[k, 0]:.3f} y: {p0[k, 1]:.3f} "
                    f"z: {p0[k, 2]:.3f} }} }}\n")
        f.write(f"mode: {'QUADCOPTER' if quad else 'PARTICLE'}\n")
        if quad:  # as the summary says: its random starts may be closer than the safe distance
            f.write("avoidance { enabled: false }\n")
        f.write("convergence { tolerance_m: 0.05 hold_s: 1 }\n")
        f.write(f"seed: {seed}\n")
    return d


def run_plot(*args):
    return subprocess.run([os.path.join(BIN, "swarm"), "plot", *args], capture_output=True,
                          text=True, timeout=300)


class SwarmPlotTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="swarm-plot-test-")
        cls.root = cls.tmp.name

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def check_figures(self, run_dir, out, expected, absent=()):
        r = run_plot(run_dir, "--out", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stderr, "")
        listed = r.stdout.split()
        for name in expected:
            path = os.path.join(out, name)
            self.assertIn(path, listed)
            self.assertTrue(os.path.isfile(path), path)
            self.assertGreater(os.path.getsize(path), 1000, path)
            with open(path, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n", path)
        for name in absent:
            self.assertFalse(os.path.exists(os.path.join(out, name)), name)
        self.assertEqual(len(listed), len(expected))

    def test_particle_run(self):
        d = make_run(self.root, "particle")
        self.check_figures(d, os.path.join(d, run_dir_names.PLOTS), COMMON, absent=QUAD)

    def test_default_out_dir_and_deterministic(self):
        d = make_run(self.root, "determinism", quad=True, seed=3)
        r1 = run_plot(d)
        self.assertEqual(r1.returncode, 0, r1.stderr)
        first = {}
        for name in COMMON + QUAD:
            with open(os.path.join(d, run_dir_names.PLOTS, name), "rb") as f:
                first[name] = f.read()
        r2 = run_plot(d)
        self.assertEqual(r2.returncode, 0, r2.stderr)
        for name in COMMON + QUAD:
            with open(os.path.join(d, run_dir_names.PLOTS, name), "rb") as f:
                self.assertEqual(f.read(), first[name], f"{name} differs between two runs")

    def test_quadcopter_run(self):
        d = make_run(self.root, "quad", quad=True)
        self.check_figures(d, os.path.join(self.root, "quad-plots"), COMMON + QUAD)

    def test_no_faults(self):
        d = make_run(self.root, "calm", faults=False, n_agents=3)
        self.check_figures(d, os.path.join(d, run_dir_names.PLOTS), COMMON, absent=QUAD)

    def expect_error(self, run_dir, file_name, words=()):
        r = run_plot(run_dir)
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertEqual(r.stdout, "")
        prefix = f"swarm plot: {os.path.join(run_dir, file_name)}: "
        self.assertTrue(r.stderr.startswith(prefix), r.stderr)
        self.assertEqual(r.stderr.count("\n"), 1, r.stderr)  # one line, no traceback
        for w in words:
            self.assertIn(w, r.stderr)
        return r.stderr

    def test_missing_run_dir(self):
        missing = os.path.join(self.root, "no-such-run")
        r = run_plot(missing)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stderr, f"swarm plot: {missing}: no such run directory\n")

    def test_missing_summary(self):
        d = make_run(self.root, "nosummary", n_agents=3, duration=1.0)
        os.remove(os.path.join(d, run_dir_names.SUMMARY))
        self.expect_error(d, run_dir_names.SUMMARY, ["missing"])

    def test_half_written_summary(self):
        d = make_run(self.root, "halfsummary", n_agents=3, duration=1.0)
        p = os.path.join(d, run_dir_names.SUMMARY)
        with open(p) as f:
            text = f.read()
        with open(p, "w") as f:
            f.write(text[:len(text) // 2])
        self.expect_error(d, run_dir_names.SUMMARY, ["not valid JSON"])

    def test_empty_events(self):
        d = make_run(self.root, "emptyevents", n_agents=3, duration=1.0)
        open(os.path.join(d, run_dir_names.EVENTS), "w").close()
        self.expect_error(d, run_dir_names.EVENTS, ["empty"])

    def test_telemetry_cut_mid_line(self):
        d = make_run(self.root, "cutline", n_agents=3, duration=1.0)
        p = os.path.join(d, run_dir_names.TELEMETRY)
        with open(p, "rb") as f:
            data = f.read()
        with open(p, "wb") as f:
            f.write(data[:len(data) - 40])  # the last line loses its end and its newline
        self.expect_error(d, run_dir_names.TELEMETRY, ["cut short"])

    def test_telemetry_short_line_in_the_middle(self):
        d = make_run(self.root, "shortline", n_agents=3, duration=1.0)
        p = os.path.join(d, run_dir_names.TELEMETRY)
        with open(p) as f:
            lines = f.read().split("\n")
        lines[10] = lines[10][:30]
        with open(p, "w") as f:
            f.write("\n".join(lines))
        self.expect_error(d, run_dir_names.TELEMETRY, ["line 11", "fields"])

    def test_telemetry_not_a_number(self):
        d = make_run(self.root, "nan-field", n_agents=3, duration=1.0)
        p = os.path.join(d, run_dir_names.TELEMETRY)
        with open(p) as f:
            lines = f.read().split("\n")
        fields = lines[20].split(",")
        fields[8] = "1.2.3"
        lines[20] = ",".join(fields)
        with open(p, "w") as f:
            f.write("\n".join(lines))
        self.expect_error(d, run_dir_names.TELEMETRY, ["line 21", "px", "1.2.3"])

    def test_scenario_is_read_by_swarm_inspect(self):
        # The scenario as run, with every default resolved: what the figures label and draw (the
        # tolerance line) comes from `swarm inspect --json`, not from the text.
        d = make_run(self.root, "resolved", n_agents=3, duration=1.0)
        inspection = record.read_scenario(d, os.path.join(BIN, "swarm"))
        self.assertEqual(inspection["resolved"]["name"], "resolved")
        self.assertEqual(inspection["resolved"]["convergence"]["tolerance_m"], 0.05)
        self.assertEqual(inspection["resolved"]["rates"]["consensus_hz"], 50)  # the default
        with open(os.path.join(d, run_dir_names.SCENARIO), "a") as f:
            f.write("# commented out: convergence { tolerance_m: 0.5 }\n")
        inspection = record.read_scenario(d, os.path.join(BIN, "swarm"))
        self.assertEqual(inspection["resolved"]["convergence"]["tolerance_m"], 0.05)

    def test_bad_scenario_is_named(self):
        d = make_run(self.root, "badscenario", n_agents=3, duration=1.0)
        with open(os.path.join(d, run_dir_names.SCENARIO), "a") as f:
            f.write("gain: -1\n")
        self.expect_error(d, run_dir_names.SCENARIO, ["swarm inspect exited 2", "gain"])

    def test_no_scenario_is_fine(self):
        d = make_run(self.root, "noscenario", n_agents=3, faults=False)
        os.remove(os.path.join(d, run_dir_names.SCENARIO))
        self.check_figures(d, os.path.join(d, run_dir_names.PLOTS), COMMON, absent=QUAD)

    def test_header_column_missing(self):
        d = make_run(self.root, "nocolumn", n_agents=3, duration=1.0)
        p = os.path.join(d, run_dir_names.GRAPH)
        with open(p) as f:
            text = f.read()
        with open(p, "w") as f:
            f.write(text.replace("lambda2,", "", 1))
        self.expect_error(d, run_dir_names.GRAPH, ["lambda2"])

    def test_telemetry_header_only(self):
        d = make_run(self.root, "headeronly", n_agents=3, duration=1.0)
        with open(os.path.join(d, run_dir_names.TELEMETRY), "w") as f:
            f.write(TELEMETRY_HEADER + "\n")
        self.expect_error(d, run_dir_names.TELEMETRY, ["no rows"])

    def test_64_agents(self):
        t0 = time.monotonic()
        d = make_run(self.root, "big", n_agents=64, duration=60.0, quad=True, seed=11,
                     proximity_m=12.0)
        t1 = time.monotonic()
        out = os.path.join(d, run_dir_names.PLOTS)
        self.check_figures(d, out, COMMON + QUAD)
        t2 = time.monotonic()
        with open(os.path.join(d, run_dir_names.TELEMETRY)) as f:
            rows = sum(1 for _ in f) - 1
        print(f"\n[64 agents, 60 s, {rows} telemetry rows] writing the run took {t1 - t0:.1f} s, "
              f"swarm plot took {t2 - t1:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print("usage: test_swarm_plot.py BUILD_BIN_DIR", file=sys.stderr)
        sys.exit(2)
    BIN = os.path.abspath(sys.argv.pop(1))
    sys.path.insert(0, os.path.join(BIN, "python"))  # the build's copy of python/qswarm
    from qswarm import record
    from qswarm import run_dir as run_dir_names
    unittest.main(verbosity=2)
