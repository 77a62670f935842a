"""swarm resilience: the three agreement laws under the same attacks by one insider that lies.

Usage (the C++ `swarm resilience` subcommand execs this):

  python3 -m qswarm.resilience --swarm BIN --preview BIN --scenario FILE --out DIR [--liar ID]

Flies FILE (default scenarios/insider_seven.txtpb: 7 agents on the complete graph, W-MSR with
F = 1) with swarm-preview, the bare laws in lockstep, once per law (edge-flow, laplacian, w-msr)
and attack (constant, drift, split), agent ID (default the highest id) lying for the scenario's
whole duration. Writes into DIR insider.png (over time, per attack: how far the farthest honest
agent is outside the honest agents' initial bounding box, and the honest agents' disagreement)
and numbers.csv (at the end of the flight), and prints the table for docs/resilience.md. The same
scenario gives the same bytes.

Exit status: 0 when everything was written; 2 for bad input (a scenario or binary, named); 3 when
DIR could not be written.
"""

import argparse
import csv
import os
import sys

from qswarm import binaries
from qswarm.drawing import import_matplotlib, save_figure

PROG = "swarm resilience"
LAWS = ("edge-flow", "laplacian", "w-msr")
ATTACKS = ("constant", "drift", "split")
COLUMNS = ["law", "attack", "outside_m", "max_outside_m", "disagreement_m", "mean_x", "mean_y",
           "mean_z"]
FIGURE = "insider.png"
NUMBERS = "numbers.csv"
FLOOR_M = 1e-12  # the figure's floor for disagreement: below it is round-off
ABOUT = {
    "constant": "a far constant: (1000, 1000, 1000) m",
    "drift": "a slow drift: its start + 0.5 m/s per axis",
    "split": "per neighbour: +1000 m to even ids, -1000 m to odd",
}


class Failure(Exception):
    def __init__(self, code, what):
        super().__init__(what)
        self.code = code
        self.what = what


def measures(np, states):
    """Per tick, of the honest agents (ticks x agents x 3): how far the farthest is outside their
    initial bounding box, and their disagreement (largest distance from their mean)."""
    lo, hi = states[0].min(axis=0), states[0].max(axis=0)
    out = np.maximum(np.maximum(lo - states, states - hi), 0.0)
    outside = np.linalg.norm(out, axis=2).max(axis=1)
    mean = states.mean(axis=1, keepdims=True)
    disagreement = np.linalg.norm(states - mean, axis=2).max(axis=1)
    return outside, disagreement


def fly_all(np, preview, scenario, liar):
    flights = {}
    for law in LAWS:
        for attack in ATTACKS:
            try:
                t, ids, states = binaries.lockstep(preview, scenario, np, law,
                                                   f"{liar}:{attack}")
            except binaries.BinaryError as e:
                raise Failure(2, str(e)) from None
            outside, disagreement = measures(np, states)
            flights[law, attack] = {"t": t, "ids": ids, "states": states, "outside": outside,
                                    "disagreement": disagreement}
    return flights


def rows(flights):
    out = []
    for law in LAWS:
        for attack in ATTACKS:
            f = flights[law, attack]
            mean = f["states"][-1].mean(axis=0)
            out.append({"law": law, "attack": attack, "outside_m": float(f["outside"][-1]),
                        "max_outside_m": float(f["outside"].max()),
                        "disagreement_m": float(f["disagreement"][-1]),
                        "mean_x": float(mean[0]), "mean_y": float(mean[1]),
                        "mean_z": float(mean[2])})
    return out


def number(v):
    """A table's number: 0 as 0, tiny or huge in e-notation, else 3 significant digits."""
    if v == 0.0:
        return "0"
    return f"{v:.1e}" if abs(v) < 1e-3 else f"{v:.3g}" if abs(v) < 1e3 else f"{v:.0f}"


def coordinate(v):
    """A mean's coordinate to the centimetre; a tiny negative is no "-0.00"."""
    text = f"{v:.2f}"
    return "0.00" if text == "-0.00" else text


def table(rows_, duration_s):
    t = f"{duration_s:g} s"
    lines = [f"| law | attack | outside at {t} [m] | most outside [m] | honest disagreement at "
             f"{t} [m] | honest mean at {t} [m] |",
             "| --- | --- | ---: | ---: | ---: | --- |"]
    for r in rows_:
        lines.append(f"| {r['law']} | {r['attack']} | {number(r['outside_m'])} | "
                     f"{number(r['max_outside_m'])} | {number(r['disagreement_m'])} | "
                     f"({coordinate(r['mean_x'])}, {coordinate(r['mean_y'])}, "
                     f"{coordinate(r['mean_z'])}) |")
    return "\n".join(lines) + "\n"


def draw(np, plt, flights, liar, n, out):
    plt.rcParams.update({"font.size": 9, "axes.titlesize": 10})
    fig, axes = plt.subplots(len(ATTACKS), 2, figsize=(11, 9.5), sharex=True)
    styles = {"edge-flow": ("tab:red", "-"), "laplacian": ("tab:orange", "--"),
              "w-msr": ("tab:blue", "-")}
    for row, attack in enumerate(ATTACKS):
        left, right = axes[row]
        for law in LAWS:
            f = flights[law, attack]
            color, ls = styles[law]
            left.plot(f["t"], f["outside"], color=color, ls=ls, label=law)
            # Below FLOOR_M is round-off (and a log axis cannot show 0): drawn at the floor.
            right.semilogy(f["t"], np.maximum(f["disagreement"], FLOOR_M), color=color, ls=ls,
                           label=law)
        left.set_ylabel("outside the honest initial box [m]")
        left.set_title(f"agent {liar} lies, {ABOUT[attack]}")
        right.set_ylabel("honest disagreement [m]")
        right.set_ylim(bottom=FLOOR_M / 2)
        right.set_title(f"{attack}: the {n - 1} honest agents' spread")
        for ax in (left, right):
            ax.grid(True, alpha=0.3)
        left.legend(loc="center right")
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"One insider of {n} on the complete graph: W-MSR (F = 1) keeps the honest agents "
                 "in their initial box; the laws that trust everyone follow the liar")
    fig.tight_layout()
    save_figure(plt, fig, os.path.join(out, FIGURE))


def write_numbers(rows_, out):
    tmp = os.path.join(out, NUMBERS + ".tmp")
    with open(tmp, "w", encoding="utf-8", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        for r in rows_:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})
    os.replace(tmp, os.path.join(out, NUMBERS))


def main(argv):
    ap = argparse.ArgumentParser(prog=PROG)
    ap.add_argument("--swarm", required=True)
    ap.add_argument("--preview", required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--liar", type=int, default=0, help="the lying agent (default: the highest id)")
    args = ap.parse_args(argv)
    mods = import_matplotlib(PROG)
    if mods is None:
        return 2
    np, plt = mods
    try:
        ins = binaries.inspect(args.swarm, args.scenario)
        ids = [int(a["id"]) for a in ins.get("agents", [])]
        liar = args.liar or max(ids)
        if liar not in ids:
            raise Failure(2, f"--liar: agent {liar} is not one of the scenario's agents "
                          f"({', '.join(map(str, ids))})")
        duration_s = float(ins["resolved"]["duration_s"])
        flights = fly_all(np, args.preview, args.scenario, liar)
        rows_ = rows(flights)
        try:
            os.makedirs(args.out, exist_ok=True)
            draw(np, plt, flights, liar, len(ids), args.out)
            write_numbers(rows_, args.out)
        except OSError as e:
            raise Failure(3, f"{e.filename or args.out}: {e.strerror}") from None
    except binaries.BinaryError as e:
        print(f"{PROG}: {e}", file=sys.stderr)
        return 2
    except Failure as e:
        print(f"{PROG}: {e.what}", file=sys.stderr)
        return e.code
    print(table(rows_, duration_s), end="")
    for name in (FIGURE, NUMBERS):
        print(os.path.join(args.out, name))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
