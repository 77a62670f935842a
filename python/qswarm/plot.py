"""swarm plot: PNG figures of one recorded swarm run.

Usage: python3 -m qswarm.plot --swarm BIN RUN_DIR [--out DIR]
(the C++ `swarm plot` subcommand execs this, with BIN itself)

Reads the run directory written by the supervisor's Recorder (common/record/recorder.cpp):
summary.json, telemetry.csv, graph.csv, events.csv and, if present, scenario.txtpb (through
`BIN inspect --json`). Writes into DIR (default RUN_DIR/plots):

  trajectories_3d.png   3D paths of the physical positions, start/end markers, the agreement point
                        (summary final_consensus_mean) and the initial average
  positions.png         x, y, z against time per agent
  graph.png             edge count, lambda_2, components (and agents present) against time
  graph_snapshots.png   the graph in the x-y plane at the times its edge set changes (at most 8)
  disagreement.png      disagreement (log axis) and spread; the drift of the consensus mean
  attitude.png          roll, pitch, yaw (ZYX Tait-Bryan), quadcopter runs only
  rotors.png            the four rotor speeds per agent, quadcopter runs only
  thrust.png            total thrust K_r * sum(w_i^2) per agent, quadcopter runs only

Fault windows from events.csv (cut..cut_end, partition..heal, loss..loss_end, kill..restart) are
shaded on every time axis; kills and late joins are vertical lines. Swarms of more than 10 agents
get a colormap and a colorbar instead of a per-agent legend.

Exit status: 0 when every figure was written (their paths are printed on stdout, one a line);
2 for a bad command line or a bad run directory, with `swarm plot: RUN_DIR/FILE: what is wrong` on
stderr. Figures are written deterministically: rerunning on the same run gives identical bytes.

Needs only numpy and matplotlib (Debian's python3-numpy, python3-matplotlib under /usr/bin/python3).
"""

import argparse
import math
import os
import sys

from qswarm import run_dir as run_dir_names
from qswarm.drawing import import_matplotlib, save_figure
from qswarm.record import RunError, load_run, parse_edges

PROG = "swarm plot"

# The airframe of every quadcopter agent: common/core/airframe.hpp, struct Airframe defaults, which
# are the paper's Table 1 (from Bouadi et al.). Scenarios cannot override them.
K_R = 2.9842e-5  # thrust coefficient K_r [N s^2/rad^2]
MASS_KG = 0.468  # m
GRAVITY = 9.81  # g [m/s^2]

MAX_SNAPSHOTS = 8
LEGEND_MAX_AGENTS = 10
LABEL_MAX_AGENTS = 16  # node ids written in the graph snapshots up to this many agents
MAX_EVENT_LABELS = 12

FAULT_STYLE = {  # kind of window -> (colour, alpha, legend label)
    "cut": ("tab:orange", 0.18, "link cut"),
    "partition": ("tab:purple", 0.15, "partition"),
    "loss": ("0.5", 0.15, "loss window"),
    "kill": ("tab:red", 0.12, "agent killed"),
}


# ---------------------------------------------------------------------------------------------
# Figures


class Plotter:
    def __init__(self, plt, np, run, out_dir):
        self.plt = plt
        self.np = np
        self.run = run
        self.out_dir = out_dir
        self.written = []
        ids = [tr.id for tr in run["tracks"]]
        for a in run["summary"].get("agents", []) or []:
            if isinstance(a, dict) and isinstance(a.get("id"), int) and a["id"] not in ids:
                ids.append(a["id"])
        self.ids = sorted(ids)
        self.n = len(self.ids)
        self.many = self.n > LEGEND_MAX_AGENTS
        self.lw = 1.3 if self.n <= LEGEND_MAX_AGENTS else (0.8 if self.n <= 32 else 0.5)
        from matplotlib import cm, colors
        if self.many:
            self.cmap = cm.get_cmap("viridis")
            lo, hi = min(self.ids), max(self.ids)
            self.norm = colors.Normalize(vmin=lo, vmax=hi if hi > lo else lo + 1)
            self.color = {i: self.cmap(self.norm(i)) for i in self.ids}
        else:
            tab = cm.get_cmap("tab10")
            self.color = {i: tab(k % 10) for k, i in enumerate(self.ids)}

    # -- helpers

    def title(self, what):
        r = self.run
        return (f"{r['name']} (seed {r['seed']}): {what}\n"
                f"{self.n} agents, {r['mode']} mode")

    def new_fig(self, nrows=1, ncols=1, size=(10, 7), **kw):
        fig, axes = self.plt.subplots(nrows, ncols, figsize=size, layout="constrained",
                                      squeeze=False, **kw)
        return fig, axes

    def shade(self, ax, label_events=False):
        r = self.run
        for kind, t0, t1, _ in r["windows"]:
            colour, alpha, _ = FAULT_STYLE[kind]
            ax.axvspan(t0, t1, color=colour, alpha=alpha, lw=0, zorder=0)
        for t, kind, label in r["marks"]:
            if kind == "kill":
                ax.axvline(t, color="tab:red", lw=0.9, zorder=1)
            elif kind == "restart":
                ax.axvline(t, color="tab:red", lw=0.7, ls="--", zorder=1)
            else:
                ax.axvline(t, color="tab:blue", lw=0.7, ls=":", zorder=1)
        if label_events and r["marks"]:
            trans = ax.get_xaxis_transform()
            for t, kind, label in r["marks"][:MAX_EVENT_LABELS]:
                ax.text(t, 0.98, " " + label, transform=trans, rotation=90, va="top", ha="left",
                        fontsize=7, color="tab:red" if kind != "late_join" else "tab:blue")

    def fault_handles(self):
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch
        kinds = []
        for kind, *_ in self.run["windows"]:
            if kind not in kinds:
                kinds.append(kind)
        h = [Patch(color=FAULT_STYLE[k][0], alpha=min(1.0, FAULT_STYLE[k][1] * 2.5),
                   label=FAULT_STYLE[k][2]) for k in kinds]
        mk = {m[1] for m in self.run["marks"]}
        if "kill" in mk:
            h.append(Line2D([], [], color="tab:red", lw=0.9, label="kill"))
        if "restart" in mk:
            h.append(Line2D([], [], color="tab:red", lw=0.7, ls="--", label="restart"))
        if "late_join" in mk:
            h.append(Line2D([], [], color="tab:blue", lw=0.7, ls=":", label="late join"))
        return h

    def agent_key(self, fig, axes, legend_ax, extra=()):
        """Per-agent legend (<= 10 agents) or a colorbar, plus the fault legend."""
        from matplotlib.lines import Line2D
        handles = list(extra) + self.fault_handles()
        if not self.many:
            handles = [Line2D([], [], color=self.color[i], lw=1.5, label=f"agent {i}")
                       for i in self.ids] + handles
        else:
            from matplotlib.cm import ScalarMappable
            sm = ScalarMappable(norm=self.norm, cmap=self.cmap)
            cb = fig.colorbar(sm, ax=axes, shrink=0.8, pad=0.01, aspect=40)
            cb.set_label(f"agent id ({self.n} agents)")
        if handles:
            legend_ax.legend(handles=handles, fontsize=7, loc="best",
                             ncol=2 if len(handles) > 6 else 1, framealpha=0.8)

    def lines(self, ax, key_fn):
        """One line per agent (segments split at gaps) as one LineCollection."""
        from matplotlib.collections import LineCollection
        np = self.np
        segs, cols = [], []
        for tr in self.run["tracks"]:
            y = key_fn(tr)
            pts = np.column_stack([tr.t, y])
            nan = np.isnan(tr.t) | np.isnan(y)
            if nan.any():
                idx = np.nonzero(nan)[0]
                bounds = [-1] + list(idx) + [len(y)]
                parts = [pts[bounds[i] + 1:bounds[i + 1]] for i in range(len(bounds) - 1)]
            else:
                parts = [pts]
            for p in parts:
                if len(p) >= 1:
                    segs.append(p)
                    cols.append(self.color[tr.id])
        if segs:
            lc = LineCollection(segs, colors=cols, linewidths=self.lw,
                                alpha=0.9 if not self.many else 0.8)
            ax.add_collection(lc)
            ax.autoscale_view()
        ax.set_xlim(0, self.run["t_end"])
        ax.grid(True, lw=0.3, alpha=0.5)

    def save(self, fig, name):
        path = os.path.join(self.out_dir, name)
        save_figure(self.plt, fig, path)
        self.written.append(path)

    # -- figures

    def trajectories(self):
        np = self.np
        fig = self.plt.figure(figsize=(10, 8), layout="constrained")
        ax = fig.add_subplot(projection="3d")
        from matplotlib.lines import Line2D
        starts, ends = [], []
        for tr in self.run["tracks"]:
            c = tr.cols
            ax.plot(c["px"], c["py"], c["pz"], color=self.color[tr.id], lw=self.lw,
                    alpha=0.9 if not self.many else 0.7)
            ok = ~np.isnan(c["px"])
            if ok.any():
                first, last = np.nonzero(ok)[0][[0, -1]]
                starts.append((c["px"][first], c["py"][first], c["pz"][first], tr.id))
                ends.append((c["px"][last], c["py"][last], c["pz"][last], tr.id))
        ms = 30 if not self.many else 10
        if starts:
            s = np.array([x[:3] for x in starts])
            ax.scatter(s[:, 0], s[:, 1], s[:, 2], marker="o", s=ms, depthshade=False,
                       c=[self.color[x[3]] for x in starts], edgecolors="k", linewidths=0.5)
            e = np.array([x[:3] for x in ends])
            ax.scatter(e[:, 0], e[:, 1], e[:, 2], marker="x", s=ms, depthshade=False,
                       c=[self.color[x[3]] for x in ends], linewidths=0.8)
        qa = self.run["summary"]["final_consensus_mean"]
        q0 = self.run["summary"]["initial_average"]
        ax.scatter([qa[0]], [qa[1]], [qa[2]], marker="*", s=220, color="gold", edgecolors="k",
                   linewidths=0.8, depthshade=False, zorder=10)
        ax.scatter([q0[0]], [q0[1]], [q0[2]], marker="D", s=60, facecolors="none",
                   edgecolors="tab:red", linewidths=1.5, depthshade=False, zorder=11)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        ax.set_title(self.title("3D trajectories (physical positions)"))
        extra = [
            Line2D([], [], ls="", marker="o", color="0.6", markeredgecolor="k", label="start"),
            Line2D([], [], ls="", marker="x", color="0.3", label="last sample"),
            Line2D([], [], ls="", marker="*", color="gold", markeredgecolor="k", markersize=12,
                   label="agreement point (final consensus mean)"
                         f" ({qa[0]:.4g}, {qa[1]:.4g}, {qa[2]:.4g})"),
            Line2D([], [], ls="", marker="D", markerfacecolor="none", markeredgecolor="tab:red",
                   label=f"initial average ({q0[0]:.4g}, {q0[1]:.4g}, {q0[2]:.4g})"),
        ]
        handles = extra
        if not self.many:
            handles = [Line2D([], [], color=self.color[i], lw=1.5, label=f"agent {i}")
                       for i in self.ids] + extra
        else:
            from matplotlib.cm import ScalarMappable
            cb = fig.colorbar(ScalarMappable(norm=self.norm, cmap=self.cmap), ax=ax, shrink=0.6,
                              pad=0.08)
            cb.set_label(f"agent id ({self.n} agents)")
        ax.legend(handles=handles, fontsize=7, loc="upper left")
        self.save(fig, "trajectories_3d.png")

    def positions(self):
        fig, axes = self.new_fig(3, 1, size=(10, 8), sharex=True)
        qa = self.run["summary"]["final_consensus_mean"]
        from matplotlib.lines import Line2D
        for k, (c, lab) in enumerate((("px", "x"), ("py", "y"), ("pz", "z"))):
            ax = axes[k, 0]
            self.shade(ax, label_events=(k == 0))
            self.lines(ax, lambda tr, c=c: tr.cols[c])
            ax.axhline(qa[k], color="k", lw=0.8, ls="--", zorder=3)
            ax.set_ylabel(f"{lab} (m)")
        axes[-1, 0].set_xlabel("time (s, simulated)")
        axes[0, 0].set_title(self.title("physical position against time"))
        self.agent_key(fig, axes, axes[0, 0],
                       [Line2D([], [], color="k", lw=0.8, ls="--", label="agreement point")])
        self.save(fig, "positions.png")

    def graph(self):
        np = self.np
        rows = self.run["graph"]
        t = np.array([r["t_s"] for r in rows])
        fig, axes = self.new_fig(3, 1, size=(10, 8), sharex=True)
        series = [("edges", "edges", "edge count"),
                  ("lambda2", "lambda2", "$\\lambda_2$ (units of the weights)"),
                  ("components", "components", "components")]
        for k, (col, label, ylab) in enumerate(series):
            ax = axes[k, 0]
            self.shade(ax, label_events=(k == 0))
            y = np.array([r[col] for r in rows])
            ax.step(t, y, where="post", color="tab:blue", lw=1.2, label=label)
            if col == "components":
                ax.step(t, [r["agents"] for r in rows], where="post", color="tab:green", lw=1.0,
                        ls="--", label="agents in the graph")
                ax.set_ylim(bottom=0)
                ax.yaxis.get_major_locator().set_params(integer=True)
                ax.legend(fontsize=7, loc="best")
            if col == "edges":
                ax.yaxis.get_major_locator().set_params(integer=True)
                handles = self.fault_handles()
                if handles:
                    ax.legend(handles=handles, fontsize=7, loc="best")
            ax.set_ylabel(ylab)
            ax.set_xlim(0, self.run["t_end"])
            ax.grid(True, lw=0.3, alpha=0.5)
        axes[-1, 0].set_xlabel("time (s, simulated)")
        axes[0, 0].set_title(self.title("communication graph against time"))
        self.save(fig, "graph.png")

    def _position_at(self, tr, t):
        np = self.np
        if tr.t_full.size == 0:
            return None
        i = int(np.searchsorted(tr.t_full, t, side="right")) - 1
        if i < 0:
            # Before its first running sample: only the initial graph uses that one.
            return None
        if t - tr.t_full[i] > 1.0:  # silent for over a second: not in the swarm now
            return None
        return tr.p_full[0][i], tr.p_full[1][i]

    def graph_snapshots(self):
        np = self.np
        from matplotlib.collections import LineCollection
        rows = [r for r in self.run["graph"] if r["agents"] > 0]
        if not rows:
            rows = self.run["graph"][:1]
        picks, prev = [], None
        for k, r in enumerate(rows):
            # The recorder writes edges in a fixed order: equal sets, equal strings.
            key = r["pairs"]
            if key != prev:
                picks.append(k)
                prev = key
        n_changes = len(picks) - 1  # the first pick is the initial graph
        if picks[-1] != len(rows) - 1:
            picks.append(len(rows) - 1)  # the final graph too
        n_candidates = len(picks)
        if len(picks) > MAX_SNAPSHOTS:
            sel = np.unique(np.round(np.linspace(0, len(picks) - 1, MAX_SNAPSHOTS)).astype(int))
            picks = [picks[i] for i in sel]
        initial = {}
        for a in self.run["summary"].get("agents", []) or []:
            if isinstance(a, dict) and isinstance(a.get("initial_position"), list) \
                    and len(a["initial_position"]) == 3:
                initial[a.get("id")] = a["initial_position"][:2]
        tracks = {tr.id: tr for tr in self.run["tracks"]}
        panels = []
        for k in picks:
            r = rows[k]
            pos = {}
            for aid in self.ids:
                p = None
                if r["t_s"] == 0.0 and aid in initial:
                    p = tuple(initial[aid])
                elif aid in tracks:
                    p = self._position_at(tracks[aid], r["t_s"])
                    if p is None and r["t_s"] == 0.0 and tracks[aid].t_full.size:
                        p = (tracks[aid].p_full[0][0], tracks[aid].p_full[1][0])
                if p is not None:
                    pos[aid] = p
            try:
                edges = parse_edges(r["edge_list"])
            except ValueError:
                raise RunError(run_dir_names.GRAPH, f"t_s {r['t_s']:g}: bad edge_list") from None
            panels.append((r, pos, edges))
        allp = np.array([p for _, pos, _ in panels for p in pos.values()] or [[0.0, 0.0]])
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        span = max(float((hi - lo).max()), 1.0)
        mid = (lo + hi) / 2
        half = span / 2 * 1.1
        ncols = min(4, len(panels))
        nrows = int(math.ceil(len(panels) / ncols))
        fig, axes = self.new_fig(nrows, ncols, size=(3.4 * ncols + 1.2, 3.5 * nrows + 0.9))
        wmax = max([w for _, _, edges in panels for _, _, w in edges] or [1.0]) or 1.0
        for idx, (r, pos, edges) in enumerate(panels):
            ax = axes[idx // ncols, idx % ncols]
            segs, widths = [], []
            for a, b, w in edges:
                if a in pos and b in pos:
                    segs.append([pos[a], pos[b]])
                    widths.append(0.4 + 2.0 * max(0.0, w) / wmax if self.n <= 32 else 0.3)
            if segs:
                ax.add_collection(LineCollection(segs, colors="0.35", linewidths=widths,
                                                 alpha=0.8 if self.n <= 32 else 0.35, zorder=1))
            ids = sorted(pos)
            if ids:
                xy = np.array([pos[i] for i in ids])
                linked = {a for a, b, _ in edges} | {b for a, b, _ in edges}
                # Filled: in the graph; hollow: no link at this time (isolated, or gone).
                face = [self.color[i] if i in linked else "white" for i in ids]
                ax.scatter(xy[:, 0], xy[:, 1], s=40 if not self.many else 10, zorder=2,
                           c=face, edgecolors=[self.color[i] if i not in linked else "k"
                                               for i in ids], linewidths=0.4 if
                           not self.many else 0.3)
                if self.n <= LABEL_MAX_AGENTS:
                    for i, (x, y) in zip(ids, xy):
                        ax.annotate(str(i), (x, y), xytext=(3, 3), textcoords="offset points",
                                    fontsize=7)
            ax.set_xlim(mid[0] - half, mid[0] + half)
            ax.set_ylim(mid[1] - half, mid[1] + half)
            ax.set_aspect("equal")
            ax.set_title(f"t = {r['t_s']:.1f} s: {len(edges)} edges, "
                         f"$\\lambda_2$ = {r['lambda2']:.3g}", fontsize=9)
            ax.tick_params(labelsize=7)
            ax.grid(True, lw=0.3, alpha=0.5)
            if idx % ncols == 0:
                ax.set_ylabel("y (m)")
            if idx // ncols == nrows - 1:
                ax.set_xlabel("x (m)")
        for idx in range(len(panels), nrows * ncols):
            axes[idx // ncols, idx % ncols].set_visible(False)
        what = (f"the graph initially, at its {n_changes} change{'s' if n_changes != 1 else ''}"
                " and at the end " if n_changes
                else "the graph (no change), initially and at the end ")
        if n_candidates > len(panels):
            what += f"({len(panels)} shown) "
        fig.suptitle(self.title(what + "in the x-y plane; line width ~ weight, hollow = no link"),
                     fontsize=10)
        self.save(fig, "graph_snapshots.png")

    def disagreement(self):
        np = self.np
        rows = [r for r in self.run["graph"] if r["agents"] > 0] or self.run["graph"]
        t = np.array([r["t_s"] for r in rows])
        d = np.array([r["disagreement_m"] for r in rows])
        sp = np.array([r["spread_m"] for r in rows])
        drift = np.array([r["mean_drift_m"] for r in rows])
        fig, axes = self.new_fig(2, 1, size=(10, 7), sharex=True,
                                 gridspec_kw={"height_ratios": [2, 1]})
        ax = axes[0, 0]
        self.shade(ax, label_events=True)
        pos = d > 0
        ax.plot(np.where(pos, t, np.nan), np.where(pos, d, np.nan), color="tab:blue", lw=1.3,
                label="disagreement (max |q_i - mean q|)")
        if self.run["mode"] == "quadcopter" or np.any(np.abs(sp - d) > 1e-9 * (1 + d)):
            ok = sp > 0
            ax.plot(np.where(ok, t, np.nan), np.where(ok, sp, np.nan), color="tab:green", lw=1.0,
                    alpha=0.8, label="physical spread (max |p_i - mean q|)")
        tol = self.run["tolerance_m"]
        if tol:
            ax.axhline(tol, color="k", lw=0.8, ls="--", label=f"tolerance {tol:g} m")
        ct = self.run["summary"].get("convergence_time_s")
        if isinstance(ct, (int, float)) and ct >= 0 and self.run["summary"].get("converged"):
            for a in axes[:, 0]:
                a.axvline(ct, color="tab:green", lw=0.9, ls="-.")
            ax.plot([], [], color="tab:green", lw=0.9, ls="-.", label=f"converged, t = {ct:.2f} s")
        if pos.any() or tol:
            ax.set_yscale("log")
        ax.set_ylabel("distance (m, log)")
        ax.set_title(self.title("disagreement and drift of the mean"))
        ax.legend(handles=ax.get_legend_handles_labels()[0] + self.fault_handles(), fontsize=7,
                  loc="best")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
        ax.set_xlim(0, self.run["t_end"])
        ax = axes[1, 0]
        self.shade(ax)
        ok = drift > 0
        ax.plot(np.where(ok, t, np.nan), np.where(ok, drift, np.nan), color="tab:purple", lw=1.2)
        if ok.any():
            ax.set_yscale("log")  # edge flow keeps the mean to ~1e-12 m: a linear axis hides it
            ax.set_ylabel("drift of the mean (m, log)\n|mean q - initial average|")
        else:
            ax.set_ylabel("drift of the mean (m)\n|mean q - initial average|")
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.set_xlabel("time (s, simulated)")
        ax.set_xlim(0, self.run["t_end"])
        self.save(fig, "disagreement.png")

    def attitude(self):
        np = self.np
        fig, axes = self.new_fig(3, 1, size=(10, 8), sharex=True)

        def euler(tr):
            c = tr.cols
            w, x, y, z = c["qw"], c["qxr"], c["qyr"], c["qzr"]
            roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
            pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
            yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
            ok = ~np.isnan(yaw)
            if ok.any():
                yaw = yaw.copy()
                yaw[ok] = np.unwrap(yaw[ok])  # a yaw through +-180 deg stays one line
            return np.degrees(roll), np.degrees(pitch), np.degrees(yaw)

        angles = {tr.id: euler(tr) for tr in self.run["tracks"]}
        for k, lab in enumerate(("roll $\\phi$ (deg)", "pitch $\\theta$ (deg)",
                                 "yaw $\\psi$ (deg, unwrapped)")):
            ax = axes[k, 0]
            self.shade(ax, label_events=(k == 0))
            self.lines(ax, lambda tr, k=k: angles[tr.id][k])
            ax.set_ylabel(lab)
        axes[-1, 0].set_xlabel("time (s, simulated)")
        axes[0, 0].set_title(self.title("attitude (ZYX Tait-Bryan angles of the body frame)"))
        self.agent_key(fig, axes, axes[0, 0])
        self.save(fig, "attitude.png")

    def rotors(self):
        fig, axes = self.new_fig(2, 2, size=(11, 7), sharex=True, sharey=True)
        hover = math.sqrt(MASS_KG * GRAVITY / (4 * K_R))
        from matplotlib.lines import Line2D
        for k in range(4):
            ax = axes[k // 2, k % 2]
            self.shade(ax, label_events=(k == 0))
            self.lines(ax, lambda tr, k=k: tr.cols[f"w{k + 1}"])
            ax.axhline(hover, color="k", lw=0.8, ls="--", zorder=3)
            ax.set_title(f"rotor {k + 1}", fontsize=9)
            if k % 2 == 0:
                ax.set_ylabel("rotor speed (rad/s)")
            if k // 2 == 1:
                ax.set_xlabel("time (s, simulated)")
        fig.suptitle(self.title("rotor speeds"), fontsize=11)
        self.agent_key(fig, axes, axes[0, 0],
                       [Line2D([], [], color="k", lw=0.8, ls="--",
                               label=f"hover {hover:.1f} rad/s")])
        self.save(fig, "rotors.png")

    def thrust(self):
        fig, axes = self.new_fig(1, 1, size=(10, 5.5))
        ax = axes[0, 0]
        from matplotlib.lines import Line2D
        self.shade(ax, label_events=True)
        self.lines(ax, lambda tr: K_R * (tr.cols["w1"] ** 2 + tr.cols["w2"] ** 2
                                         + tr.cols["w3"] ** 2 + tr.cols["w4"] ** 2))
        weight = MASS_KG * GRAVITY
        ax.axhline(weight, color="k", lw=0.8, ls="--", zorder=3)
        ax.set_ylabel("total thrust "
                      "$K_r\\,(\\omega_1^2 + \\omega_2^2 + \\omega_3^2 + \\omega_4^2)$ (N)")
        ax.set_xlabel("time (s, simulated)")
        ax.set_title(self.title("total rotor thrust"))
        self.agent_key(fig, axes, ax,
                       [Line2D([], [], color="k", lw=0.8, ls="--",
                               label=f"weight m g = {weight:.3f} N")])
        self.save(fig, "thrust.png")


# ---------------------------------------------------------------------------------------------


def main(argv):
    parser = argparse.ArgumentParser(prog=PROG, description="Write PNG figures of a swarm run.")
    parser.add_argument("run_dir", metavar="RUN_DIR")
    parser.add_argument("--out", metavar="DIR", help="output directory (default RUN_DIR/plots)")
    parser.add_argument("--swarm", metavar="BIN", required=True,
                        help="the swarm binary, which reads the run's scenario (swarm inspect)")
    args = parser.parse_args(argv)  # exits 2 on a bad command line
    run_dir = args.run_dir

    libs = import_matplotlib(PROG)
    if libs is None:
        return 2
    np, plt = libs

    try:
        run = load_run(run_dir, np, args.swarm)
    except RunError as e:
        where = os.path.join(run_dir, e.name) if e.name else run_dir
        print(f"{PROG}: {where}: {e.what}", file=sys.stderr)
        return 2

    out_dir = args.out or os.path.join(run_dir, run_dir_names.PLOTS)
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as e:
        print(f"{PROG}: {out_dir}: cannot create the output directory: {e.strerror}",
              file=sys.stderr)
        return 2

    plt.rcParams.update({"font.size": 9, "axes.titlesize": 10, "svg.hashsalt": "swarm",
                         "path.simplify": True})
    p = Plotter(plt, np, run, out_dir)
    try:
        p.trajectories()
        p.positions()
        p.graph()
        p.graph_snapshots()
        p.disagreement()
        if run["quad"]:
            p.attitude()
            p.rotors()
            p.thrust()
    except OSError as e:
        print(f"{PROG}: {out_dir}: cannot write a figure: {e.strerror}", file=sys.stderr)
        return 2
    for path in p.written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
