"""The paper's figures: the rendezvous pairs (figures 1 to 6), the section 4 maneuvers (7 to 12)."""

import math
import os

from qswarm.drawing import save_figure
from qswarm.paper_numbers import fmt_vec, settle_time

SOLID, DASHED = "-", "--"
COLORS = ["tab:blue", "tab:orange", "tab:green", "tab:red"]


class Figures:
    def __init__(self, plt, np, out):
        self.plt, self.np, self.out = plt, np, out
        self.written = []

    def save(self, fig, name):
        save_figure(self.plt, fig, os.path.join(self.out, name))
        self.written.append(name)

    def rendezvous_3d(self, name, title, a, b, label_a, label_b, q):
        fig = self.plt.figure(figsize=(8, 6.5), layout="constrained")
        ax = fig.add_subplot(projection="3d")
        for run, style in ((a, SOLID), (b, DASHED)):
            for k, agent in enumerate(sorted(run["tracks_full"])):
                t, p = run["tracks_full"][agent]
                ax.plot(p[:, 0], p[:, 1], p[:, 2], style, color=COLORS[k % 4], lw=1.3)
                if style == SOLID:
                    ax.scatter(*p[0], color=COLORS[k % 4], s=18, marker="o")
                    ax.text(*p[0], f"  {agent}", fontsize=8)
        ax.scatter(*q, color="k", marker="*", s=80)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_zlabel("z [m]")
        from matplotlib.lines import Line2D
        handles = [Line2D([], [], color="0.3", ls=SOLID, label=label_a),
                   Line2D([], [], color="0.3", ls=DASHED, label=label_b),
                   Line2D([], [], color="k", marker="*", ls="", label=f"agreement {fmt_vec(q)}")]
        handles += [Line2D([], [], color=COLORS[k], lw=2, label=f"agent {k + 1}")
                    for k in range(len(a["tracks_full"]))]
        ax.legend(handles=handles, fontsize=8, loc="upper left")
        ax.set_title(title, fontsize=10)
        self.save(fig, name)

    def agent1_xyz(self, name, title, a, b, label_a, label_b, q, marks=()):
        """Agent 1's x, y, z against time for both runs; with `marks` (edge additions of run b) a
        second row shows the first second."""
        rows = 2 if marks else 1
        fig, axes = self.plt.subplots(rows, 3, figsize=(13, 4 * rows), layout="constrained",
                                      squeeze=False)
        unit = "paper time units" if a["gain"] != 1.0 or b["gain"] != 1.0 else "s"
        # Up to when the slower run's agent 1 is within 0.5 % of its start distance, and a half.
        t_show = max(settle_time(*run["tracks_full"][1], q, 0.005) * run["gain"] for run in (a, b))
        for row in range(rows):
            for run, style, label in ((a, SOLID, label_a), (b, DASHED, label_b)):
                t, p = run["tracks_full"][1]
                for c in range(3):
                    axes[row][c].plot(t * run["gain"], p[:, c], style, lw=1.4, label=label,
                                      color="tab:blue" if style == SOLID else "tab:orange")
            for c, axis in enumerate("xyz"):
                ax = axes[row][c]
                ax.axhline(q[c], color="k", lw=0.6, ls=":", label=f"agreement {axis} = {q[c]:g}")
                for t_mark, _ in marks:
                    ax.axvline(t_mark * b["gain"], color="tab:orange", lw=0.7, alpha=0.7)
                ax.set_xlabel(f"t [{unit}]")
                ax.set_ylabel(f"{axis} of agent 1 [m]")
                ax.grid(True, lw=0.3, alpha=0.5)
                ax.set_xlim(0, 1.5 * t_show if row == 0 else 1.0)
        if marks:
            axes[0][0].plot([], [], color="tab:orange", lw=0.7, label="edge added (dashed run)")
            axes[1][1].set_title("the first second", fontsize=9)
        axes[0][0].legend(fontsize=8)
        fig.suptitle(title, fontsize=10)
        self.save(fig, name)


def draw_maneuver_figures(fig, np, single, dyn, particles, q3):
    plt = fig.plt
    s = single[1]
    # Paper figure 7: position in space and the orientation angles.
    f = plt.figure(figsize=(9, 9), layout="constrained")
    ax = f.add_subplot(2, 1, 1, projection="3d")
    ax.plot(s["x"], s["y"], s["z"], color="tab:blue", lw=1.6)
    for seg, colour in (("climb", "tab:blue"), ("yaw", "tab:green"), ("body_x", "tab:red")):
        k = [i for i, v in enumerate(s["segment"]) if v == seg]
        if k:
            ax.scatter(s["x"][k[0]], s["y"][k[0]], s["z"][k[0]], color=colour, s=25,
                       label=f"{seg.replace('_', ' ')} starts, t = {s['t_s'][k[0]]:g} s")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_xlim(-1, 1)
    ax.legend(fontsize=8)
    ax.set_title("Rise 12 s, yaw pi/2 in 4 s, fly 4 s along body x: position", fontsize=10)
    ax2 = f.add_subplot(2, 1, 2)
    for key, label, colour in (("roll", "roll phi", "tab:blue"), ("pitch", "pitch theta",
                                                                  "tab:orange"),
                               ("yaw", "yaw psi", "tab:green")):
        ax2.plot(s["t_s"], s[key], color=colour, lw=1.4, label=label)
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("angle [rad]")
    ax2.grid(True, lw=0.3, alpha=0.5)
    ax2.legend(fontsize=8)
    ax2.set_title("orientation angles (ZYX)", fontsize=10)
    fig.save(f, "fig07_maneuver_path_and_attitude.png")

    # Paper figure 8: the controls.
    f, axes = plt.subplots(2, 1, figsize=(9, 7), layout="constrained", sharex=True)
    for i in range(4):
        axes[0].plot(s["t_s"], s[f"w{i + 1}"], lw=1.3, color=COLORS[i],
                     ls=(SOLID if i < 2 else DASHED), label=f"omega_{i + 1}")
    axes[0].set_ylabel("rotor speed [rad/s]")
    axes[0].legend(fontsize=8, ncol=4)
    axes[0].grid(True, lw=0.3, alpha=0.5)
    axes[0].set_title("Rise-yaw-fly: the four rotor speeds", fontsize=10)
    axes[1].plot(s["t_s"], s["thrust_N"], color="k", lw=1.3)
    axes[1].set_ylabel("total thrust [N]")
    axes[1].set_xlabel("t [s]")
    axes[1].grid(True, lw=0.3, alpha=0.5)
    axes[1].set_title("total thrust K_r sum omega_i^2", fontsize=10)
    fig.save(f, "fig08_maneuver_controls.png")

    # Paper figure 9: the 3-drone paths (point agents flown by the swarm; the dynamic ones dashed).
    f = plt.figure(figsize=(8, 6), layout="constrained")
    ax = f.add_subplot()
    for k, agent in enumerate(sorted(particles)):
        t, p = particles[agent]
        ax.plot(p[:, 0], p[:, 1], SOLID, color=COLORS[k], lw=1.6,
                label=f"drone {agent}, point agent")
        d = dyn[agent]
        ax.plot(d["x"], d["y"], DASHED, color="k", lw=0.9)
        ax.scatter(p[0, 0], p[0, 1], color=COLORS[k], s=30)
        yaw0 = d["yaw"][0]
        ax.annotate("", xy=(p[0, 0] + 1.2 * math.cos(yaw0), p[0, 1] + 1.2 * math.sin(yaw0)),
                    xytext=(p[0, 0], p[0, 1]), arrowprops={"arrowstyle": "->", "color":
                                                           COLORS[k]})
    ax.plot([], [], DASHED, color="k", lw=0.9, label="with dynamics (yaw, then body x)")
    ax.scatter(*q3[:2], marker="*", color="k", s=90, label=f"rendezvous {fmt_vec(q3)}")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=8)
    ax.set_title("Three drones on K_3 meet at the average (arrows: initial heading); z = 0",
                 fontsize=10)
    fig.save(f, "fig09_rendezvous3_paths.png")

    # Paper figure 10: yaw over time.
    f, ax = plt.subplots(figsize=(8, 4), layout="constrained")
    for k, agent in enumerate(sorted(dyn)):
        d = dyn[agent]
        # Unwrapped: a yaw through pi is a turn, not a 2 pi jump.
        ax.plot(d["t_s"], np.unwrap(d["yaw"]), color=COLORS[k], lw=1.4, label=f"drone {agent}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("yaw psi [rad]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=8)
    ax.set_title("Yaw of each drone: 4 s of yaw Lemma, then body-x flight, then hover", fontsize=10)
    fig.save(f, "fig10_rendezvous3_yaw.png")

    # Paper figure 11: controls per drone.
    f, axes = plt.subplots(len(dyn), 2, figsize=(11, 3 * len(dyn)), layout="constrained",
                           squeeze=False)
    for k, agent in enumerate(sorted(dyn)):
        d = dyn[agent]
        for i in range(4):
            axes[k][0].plot(d["t_s"], d[f"w{i + 1}"], lw=1.2, color=COLORS[i],
                            ls=(SOLID if i < 2 else DASHED), label=f"omega_{i + 1}")
        axes[k][0].set_ylabel(f"drone {agent}: rotor [rad/s]")
        axes[k][1].plot(d["t_s"], d["thrust_N"], color="k", lw=1.2)
        axes[k][1].set_ylabel(f"drone {agent}: thrust [N]")
        for a in axes[k]:
            a.grid(True, lw=0.3, alpha=0.5)
    axes[0][0].legend(fontsize=8, ncol=4)
    axes[-1][0].set_xlabel("t [s]")
    axes[-1][1].set_xlabel("t [s]")
    f.suptitle("Rotor speeds and total thrust of each drone", fontsize=10)
    fig.save(f, "fig11_rendezvous3_controls.png")

    # Paper figure 12: x(t), y(t) with dynamics (dashed) and without (solid).
    f, axes = plt.subplots(1, 2, figsize=(12, 4), layout="constrained")
    for k, agent in enumerate(sorted(dyn)):
        t, p = particles[agent]
        d = dyn[agent]
        for c, key in enumerate("xy"):
            axes[c].plot(t, p[:, c], SOLID, color=COLORS[k], lw=1.4, label=f"drone {agent}")
            axes[c].plot(d["t_s"], d[key], DASHED, color=COLORS[k], lw=1.2)
    for c, key in enumerate("xy"):
        axes[c].set_xlabel("t [s]")
        axes[c].set_ylabel(f"{key} [m]")
        axes[c].grid(True, lw=0.3, alpha=0.5)
    axes[0].plot([], [], DASHED, color="0.3", label="with dynamics")
    axes[0].legend(fontsize=8)
    f.suptitle("Two ways to the rendezvous: agreement flow of points (solid), the paper's "
               "primitives with dynamics (dashed)", fontsize=10)
    fig.save(f, "fig12_rendezvous3_with_without_dynamics.png")
