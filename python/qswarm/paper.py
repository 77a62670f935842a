"""swarm paper: the paper's figures, flown by our swarm, and a report beside the paper's numbers.

Usage (the C++ `swarm paper` subcommand execs this after it has simulated the section 4 maneuvers
into RUNS/maneuvers/):

  python3 -m qswarm.paper --swarm BIN --preview BIN --scenarios DIR --runs RUNS --out OUT
                          [--fly] [--time-scale K] [--domain D]

With --fly every rendezvous scenario of DIR is flown by the multi-process swarm (`BIN run`, one
process per agent, DDS on loopback) into RUNS/<scenario>/; without it the runs already in RUNS are
drawn again. Writes into OUT the figures (figNN_*.png), report.md and the README's picture
(swarm_quadcopters_3d.png). Nothing written depends on the date or on where RUNS is, so drawing the
same runs again gives byte-identical files.

Exit status: 0 when every run converged and everything was written; 1 when a run did not converge
(nothing is written then: a report over a failed run would lie); 2 for bad input (a missing or
malformed run, named); 3 when OUT could not be written.
"""

import argparse
import csv
import errno
import fcntl
import os
import subprocess
import sys

from qswarm import binaries, plot
from qswarm import run_dir as run_dir_names
from qswarm.drawing import import_matplotlib
from qswarm.paper_figures import Figures, draw_maneuver_figures
from qswarm.paper_numbers import RUNS, proximity_additions, threshold_m
from qswarm.paper_report import report
from qswarm.record import RunError, load_run

PROG = "swarm paper"
QUADCOPTER_TIME_SCALE = 2.0  # quadcopter runs fly at most this fast (500 Hz physics per agent)

MANEUVER_COLUMNS = ["drone", "t_s", "x", "y", "z", "roll", "pitch", "yaw", "w1", "w2", "w3", "w4",
                    "thrust_N", "yaw_torque_Nm", "segment"]


class Failure(Exception):
    def __init__(self, code, what):
        super().__init__(what)
        self.code = code
        self.what = what


# ---------------------------------------------------------------------------------------------
# Flying and reading


def fly(swarm, scenarios, runs, stem, time_scale, domain):
    path = os.path.join(scenarios, stem + ".txtpb")
    if not os.path.isfile(path):
        raise Failure(2, f"{path}: missing (every figure of the paper has a scenario there)")
    out = os.path.join(runs, stem)
    scale = min(time_scale, QUADCOPTER_TIME_SCALE) if stem.endswith("_quadcopter") else time_scale
    print(f"{PROG}: flying {stem} ({os.path.basename(path)}, time scale {scale:g})", flush=True)
    cmd = [swarm, "run", path, "--out", out, "--time-scale", f"{scale:g}", "--quiet"]
    if domain is not None:
        cmd += ["--domain", str(domain)]
    try:
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    except OSError as e:
        raise Failure(2, f"{swarm}: cannot run ({e.strerror})") from None
    if r.returncode != 0:
        # swarm run: 1 not converged, 3 record incomplete; anything else is bad input or a crash.
        raise Failure(r.returncode if r.returncode in (1, 3) else 2,
                      f"{stem}: swarm run exited {r.returncode}, so no report is written:\n"
                      + r.stdout.strip())


def load(swarm, preview, runs, stem, np):
    """One rendezvous run, its scenario as flown (`swarm inspect --json` of its scenario.txtpb, so
    a redraw depends only on the runs, not on today's scenario files) and, on a fixed graph, the
    same scenario flown by the laws in lockstep (swarm-preview)."""
    run_dir = os.path.join(runs, stem)
    try:
        run = load_run(run_dir, np, swarm)
    except RunError as e:
        raise Failure(2, f"{os.path.join(run_dir, e.name)}: {e.what}") from None
    if not run["summary"].get("converged"):
        raise Failure(1, f"{run_dir}: the run did not converge "
                         f"({run['summary'].get('end_reason', 'no reason given')})")
    if run["inspection"] is None:
        path = os.path.join(run_dir, run_dir_names.SCENARIO)
        raise Failure(2, f"{path}: "
                         + ("empty" if os.path.exists(path) else os.strerror(errno.ENOENT)))
    resolved = run["scenario"]
    run["gain"] = float(resolved["gain"])
    run["fixed"] = resolved["topology"]["policy"] == "FIXED"
    run["consensus_hz"] = float(resolved["rates"]["consensus_hz"])
    run["dir"] = run_dir
    run["lockstep"] = None
    if run["fixed"]:
        try:
            run["lockstep"] = binaries.lockstep(
                preview, os.path.join(run_dir, run_dir_names.SCENARIO), np)
        except binaries.BinaryError as e:
            raise Failure(2, str(e)) from None
    return run


def read_maneuver(path, np):
    if not os.path.isfile(path):
        raise Failure(2, f"{path}: missing (`swarm paper` without --from writes it)")
    try:
        with open(path, encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            raise Failure(2, f"{path}: no rows")
        missing = [c for c in MANEUVER_COLUMNS if c not in rows[0]]
        if missing:
            raise Failure(2, f"{path}: lacks the columns {', '.join(missing)}")
        out = {}
        for r in rows:
            d = out.setdefault(int(r["drone"]), {k: [] for k in MANEUVER_COLUMNS if k != "drone"})
            for k in d:
                d[k].append(r[k] if k == "segment" else float(r[k]))
    except OSError as e:
        raise Failure(2, f"{path}: {e.strerror}") from None
    except (ValueError, TypeError):
        raise Failure(2, f"{path}: a field is not a number (a half-written file?)") from None
    for d in out.values():
        for k in d:
            if k != "segment":
                d[k] = np.array(d[k])
    return out


def read_segments(path):
    """{(file, drone): [(segment, start_s, duration_s)]} from segments.csv."""
    if not os.path.isfile(path):
        raise Failure(2, f"{path}: missing (`swarm paper` without --from writes it)")
    out, current = {}, None
    try:
        with open(path, encoding="utf-8") as f:
            for line in f.read().splitlines()[1:]:
                if line.startswith("# "):
                    current = line[2:].strip()
                    continue
                drone, seg, start, dur, _ = line.split(",")
                out.setdefault((current, int(drone)), []).append((seg, float(start), float(dur)))
    except OSError as e:
        raise Failure(2, f"{path}: {e.strerror}") from None
    except ValueError:
        raise Failure(2, f"{path}: malformed line (a half-written file?)") from None
    return out


# ---------------------------------------------------------------------------------------------
# Main


def main(argv):
    ap = argparse.ArgumentParser(prog=PROG)
    ap.add_argument("--swarm", required=True)
    ap.add_argument("--preview", required=True)
    ap.add_argument("--scenarios", required=True)
    ap.add_argument("--runs", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--fly", action="store_true")
    ap.add_argument("--time-scale", type=float, default=4.0)
    ap.add_argument("--domain", type=int)
    args = ap.parse_args(argv)
    libs = import_matplotlib(PROG)
    if libs is None:
        return 2
    np, plt = libs
    try:
        return run(args, np, plt)
    except Failure as e:
        print(f"{PROG}: {e.what}", file=sys.stderr)
        return e.code
    except OSError as e:
        print(f"{PROG}: {e.filename}: {e.strerror}", file=sys.stderr)
        return 3


def run(args, np, plt):
    if args.fly:
        for stem in RUNS:
            fly(args.swarm, args.scenarios, args.runs, stem, args.time_scale, args.domain)
    runs, spectra = {}, {}
    for stem in RUNS:
        runs[stem] = load(args.swarm, args.preview, args.runs, stem, np)
        # Every agent's consensus state at full rate (running samples, time-sorted).
        runs[stem]["tracks_full"] = {tr.id: (tr.t_full, tr.q_full) for tr in runs[stem]["tracks"]}
        spectra[stem] = runs[stem]["inspection"]
    man = os.path.join(args.runs, run_dir_names.MANEUVERS)
    single = read_maneuver(os.path.join(man, run_dir_names.SINGLE_AGENT), np)
    dyn = read_maneuver(os.path.join(man, run_dir_names.RENDEZVOUS_DYNAMICS), np)
    segments = read_segments(os.path.join(man, run_dir_names.SEGMENTS))
    for agent in dyn:
        if (run_dir_names.RENDEZVOUS_DYNAMICS, agent) not in segments:
            raise Failure(2, f"{os.path.join(man, run_dir_names.SEGMENTS)}: no segments of drone "
                             f"{agent}")
        dyn[agent]["segments"] = segments[(run_dir_names.RENDEZVOUS_DYNAMICS, agent)]
    if (run_dir_names.SINGLE_AGENT, 1) not in segments:
        raise Failure(2, f"{os.path.join(man, run_dir_names.SEGMENTS)}: no segments of the "
                         "single agent")

    # Everything is drawn into a staging directory first and moved into OUT only when all of it
    # was written, so a failed regeneration never leaves OUT half new.
    os.makedirs(args.out, exist_ok=True)
    stage = os.path.join(args.out, f".staging-{os.getpid()}")
    os.makedirs(stage, exist_ok=True)
    try:
        written = draw_all(args, np, plt, runs, spectra, single, dyn, stage)
        # Two `swarm paper` at once: each moves its whole set under a lock on OUT, so OUT ends as
        # one complete set, never figures of one and the report of the other.
        out_fd = os.open(args.out, os.O_RDONLY)
        try:
            fcntl.flock(out_fd, fcntl.LOCK_EX)
            for name in written:
                os.replace(os.path.join(stage, name), os.path.join(args.out, name))
        finally:
            os.close(out_fd)
    finally:
        for name in os.listdir(stage):
            os.remove(os.path.join(stage, name))
        os.rmdir(stage)
    for name in written:
        print(os.path.join(args.out, name))
    return 0


def draw_all(args, np, plt, runs, spectra, single, dyn, out):
    plt.rcParams.update({"font.size": 9, "axes.titlesize": 10, "path.simplify": True})
    fig = Figures(plt, np, out)
    pairs = [
        ("unweighted", "unweighted_l2", "L_1 (solid)", "L_2 (dashed)",
         "2.6.1 unweighted networks", "01", "02"),
        ("weighted_baseline", "weighted", "unweighted L_1 (solid)", "weighted by distance (dashed)",
         "2.7.1 unweighted vs weighted", "03", "04"),
        ("time_varying_baseline", "time_varying", "fixed unweighted (solid)",
         "time-varying, distance weights (dashed)", "2.7.2 fixed vs time-varying", "05", "06"),
    ]
    for a, b, la, lb, what, n3d, nxyz in pairs:
        q = RUNS[a]["q"]
        fig.rendezvous_3d(f"fig{n3d}_{b}_3d.png", f"Paper {what}: four agents, each its own "
                          "process over DDS", runs[a], runs[b], la, lb, q)
        marks = ([(t, 0) for t, _, _ in
                  proximity_additions(runs[b], threshold_m(runs[b]), spectra[b]["edges"])]
                 if b == "time_varying" else ())
        fig.agent1_xyz(f"fig{nxyz}_{b}_agent1_xyz.png", f"Paper {what}: agent 1's x, y, z",
                       runs[a], runs[b], la, lb, q, marks)
    draw_maneuver_figures(fig, np, single, dyn, runs["rendezvous3"]["tracks_full"],
                          RUNS["rendezvous3"]["q"])
    # The README's picture: the time-varying rendezvous flown by four quadcopters.
    p = plot.Plotter(plt, np, runs["time_varying_quadcopter"], out)
    p.trajectories()
    os.replace(os.path.join(out, "trajectories_3d.png"),
               os.path.join(out, "swarm_quadcopters_3d.png"))
    fig.written.append("swarm_quadcopters_3d.png")

    text = report(runs, spectra, single, dyn, np)
    tmp = os.path.join(out, "report.md.tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, os.path.join(out, "report.md"))
    return fig.written + ["report.md"]


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
