"""The paper's printed numbers, and ours from the runs: spectra, decay rates (of the swarm, and of
the law in lockstep as swarm-preview flies it), settling times, edge additions, distances from
straight lines, and how the report prints them."""

import math

# The rendezvous runs: scenario file stem -> what the paper printed for it.
#   q: the agreement point it printed; eig: the initial eigenvalues it printed.
RUNS = {
    "unweighted": {"q": (10.25, 9.75, 29.25), "eig": (0, 1, 3, 4)},
    "unweighted_l2": {"q": (10.25, 9.75, 29.25), "eig": (0, 0.586, 2, 3.414)},
    "weighted_baseline": {"q": (9, 12.75, 30.25), "eig": (0, 1, 3, 4)},
    "weighted": {"q": (9, 12.75, 30.25), "eig": (0, 13.060, 42.248, 62.558)},
    # The paper prints {0, 1, 3, 4} for this network, which is L_1's spectrum, not this one's.
    "time_varying_baseline": {"q": (15.25, 10.25, 31), "eig": (0, 1, 3, 4)},
    "time_varying": {"q": (15.25, 10.25, 31), "eig": (0, 6.234, 19.385, 37.655)},
    "rendezvous3": {"q": (5, 6, 0), "eig": (0, 3, 3)},
    "time_varying_quadcopter": {"q": (15.25, 10.25, 31), "eig": (0, 6.234, 19.385, 37.655)},
}
PAPER_FINAL_EIG = (0, 0.190, 0.196, 0.207)  # 2.7.2, "near the rendezvous agreement"


def threshold_m(run):
    """The proximity threshold of a run's scenario as flown (topology.threshold_m)."""
    return float(run["scenario"]["topology"]["threshold_m"])


def fmt_hz(runs):
    """The runs' consensus rates for the text: "50", or "50 and 100" when they differ."""
    return " and ".join(f"{hz:g}" for hz in sorted({run["consensus_hz"] for run in runs}))


def laplacian_eigs(n, edges, np):
    L = np.zeros((n, n))
    for a, b, w in edges:
        L[a - 1, b - 1] -= w
        L[b - 1, a - 1] -= w
        L[a - 1, a - 1] += w
        L[b - 1, b - 1] += w
    return np.sort(np.linalg.eigvalsh(L))


def fitted_rate(t, d, np):
    """-slope of ln(d) against t while d falls from 30 % to 1 % of its largest value."""
    top = d.max()
    sel = (d < 0.3 * top) & (d > 0.01 * top)
    if sel.sum() < 5:
        return float("nan")
    return -np.polyfit(t[sel], np.log(d[sel]), 1)[0]


def decay_rate(run, np):
    """The measured exponential rate of the disagreement (graph.csv), per paper time unit."""
    g = [r for r in run["graph"] if r["agents"] == max(x["agents"] for x in run["graph"])]
    t = np.array([r["t_s"] for r in g]) * run["gain"]
    return fitted_rate(t, np.array([r["disagreement_m"] for r in g]), np)


def lockstep_rate(run, np):
    """The decay rate of the law in lockstep (run["lockstep"], from swarm-preview), fitted as the
    swarm's is, per paper time unit."""
    t, _, hist = run["lockstep"]
    d = np.max(np.linalg.norm(hist - hist.mean(axis=1, keepdims=True), axis=2), axis=1)
    return fitted_rate(t * run["gain"], d, np)


def lockstep_offset(run, agent):
    """Largest distance of one agent's lockstep path from the straight segment to the average."""
    _, ids, hist = run["lockstep"]
    path = hist[:, ids.index(agent), :]
    return max_offset_from_segment(path, path[0], hist[0].mean(axis=0))


def first_moves(run):
    """{agent: swarm time of its first update} (its consensus state first changed)."""
    out = {}
    for a, (t, q) in run["tracks_full"].items():
        out[a] = next((float(tt) for tt, p in zip(t, q) if math.dist(p, q[0]) > 1e-9),
                      float("nan"))
    return out


def settle_time(t, q, target, frac):
    """First time after which |q - target| stays below frac of its initial value."""
    dist = [math.dist(p, target) for p in q]
    limit = frac * dist[0]
    last_above = None
    for k, d in enumerate(dist):
        if d > limit:
            last_above = k
    if last_above is None:
        return float(t[0])
    if last_above + 1 >= len(t):
        return float("nan")
    return float(t[last_above + 1])


def proximity_additions(run, threshold_m, initial_edges):
    """[(t, a, b)]: when each pair of agents not linked at the start first came within threshold_m
    of each other (their consensus states at the same tick, from telemetry): the sticky proximity
    edges as the agents saw them, at the agents' tick resolution rather than the recorder's."""
    initial = {(min(e[0], e[1]), max(e[0], e[1])) for e in initial_edges}
    at = {a: {round(float(t), 6): q for t, q in zip(*run["tracks_full"][a])}
          for a in run["tracks_full"]}
    ids = sorted(at)
    out = []
    for i, a in enumerate(ids):
        for b in ids[i + 1:]:
            if (a, b) in initial:
                continue
            for t in sorted(set(at[a]) & set(at[b])):
                if math.dist(at[a][t], at[b][t]) <= threshold_m:
                    out.append((t, a, b))
                    break
    return sorted(out)


def fmt_vec(v, digits=6):
    def one(x):
        text = f"{x:.{digits}f}".rstrip("0").rstrip(".")
        return "0" if text in ("-0", "0", "") else text
    return "(" + ", ".join(one(x) for x in v) + ")"


def fmt_eig(v):
    return "{" + ", ".join(f"{x:.3f}" if abs(x) > 5e-4 else "0" for x in v) + "}"


def max_offset_from_segment(p, a, b):
    """Largest distance of the points p (n x 3) from the segment a-b."""
    ab = [b[k] - a[k] for k in range(3)]
    n2 = sum(x * x for x in ab)
    worst = 0.0
    for pt in p:
        ap = [pt[k] - a[k] for k in range(3)]
        u = max(0.0, min(1.0, sum(ap[k] * ab[k] for k in range(3)) / n2)) if n2 > 0 else 0.0
        worst = max(worst, math.dist(pt, [a[k] + u * ab[k] for k in range(3)]))
    return worst


def run_numbers(run, spectrum, paper, np):
    s = run["summary"]
    q = s["final_consensus_mean"]
    t1, p1 = run["tracks_full"][1]
    return {
        "q": q, "q_err": math.dist(q, paper["q"]), "drift": s.get("average_drift_m", float("nan")),
        "eig": spectrum["eigenvalues"], "lambda2": spectrum["lambda2"],
        "t_conv": s.get("convergence_time_s", float("nan")), "gain": run["gain"],
        "rate": decay_rate(run, np),
        "lockstep": lockstep_rate(run, np) if run["lockstep"] else float("nan"),
        "settle1": settle_time(t1, p1, paper["q"], 0.01) * run["gain"],
        "start": first_moves(run)[1],
    }
