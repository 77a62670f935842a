"""Reading one run directory (written by the supervisor's Recorder, common/record/): every file is
checked, and a problem is a RunError naming the file and what is wrong with it."""

import csv
import json
import math
import os
import re

from qswarm import binaries
from qswarm import run_dir as run_dir_names

TELEMETRY_COLUMNS = ["stamp_s", "id", "seq", "phase", "mode", "qx", "qy", "qz", "px", "py", "pz",
                     "vx", "vy", "vz", "qw", "qxr", "qyr", "qzr", "w1", "w2", "w3", "w4",
                     "total_weight", "links", "age_ms"]
GRAPH_COLUMNS = ["t_s", "agents", "edges", "lambda2", "components", "disagreement_m",
                 "mean_drift_m", "min_separation_m", "spread_m", "edge_list"]
EVENT_COLUMNS = ["t_s", "kind", "agent", "detail"]
SUMMARY_KEYS = ["scenario", "seed", "initial_average", "final_consensus_mean"]

PHASE_RUNNING = 1
MODE_QUADCOPTER = 1

MAX_POINTS_PER_AGENT = 1500  # telemetry is decimated to at most this many points per agent


class RunError(Exception):
    """A problem with one file of the run directory (exit 2)."""

    def __init__(self, name, what):
        super().__init__(f"{name}: {what}")
        self.name = name
        self.what = what


# ---------------------------------------------------------------------------------------------
# Reading the run directory


def _read_text(run_dir, name, required=True):
    path = os.path.join(run_dir, name)
    if not os.path.exists(path):
        if required:
            raise RunError(name, "missing (not a complete run directory?)")
        return None
    if not os.path.isfile(path):
        raise RunError(name, "not a regular file")
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise RunError(name, f"cannot read: {e.strerror}") from None
    if not data.strip():
        if required:
            raise RunError(name, "empty")
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise RunError(name, f"not UTF-8 text (byte {e.start}); corrupt?") from None


def _csv_lines(name, text, columns, allow_no_rows=False):
    """Splits a CSV file into (header index map, data lines); checks header and completeness."""
    if not text.endswith("\n"):
        n = text.count("\n") + 1
        raise RunError(name, f"line {n} is cut short (no newline at the end): "
                             "a half-written file? (was the run interrupted?)")
    lines = text.split("\n")
    lines.pop()  # after the final newline
    while lines and not lines[-1].strip():
        lines.pop()
    header = [h.strip() for h in lines[0].split(",")]
    missing = [c for c in columns if c not in header]
    if missing:
        raise RunError(name, "header lacks column" + ("s " if len(missing) > 1 else " ")
                       + ", ".join(missing) + f" (header is: {lines[0].strip()})")
    if len(lines) < 2 and not allow_no_rows:
        raise RunError(name, "has a header but no rows")
    return {h: i for i, h in enumerate(header)}, len(header), lines[1:]


def _bad_field(name, lineno, col_name, value):
    shown = value if len(value) <= 30 else value[:27] + "..."
    return RunError(name, f"line {lineno}: column {col_name}: '{shown}' is not a number "
                          "(corrupt or half-written file?)")


def read_telemetry(run_dir, np):
    name = run_dir_names.TELEMETRY
    text = _read_text(run_dir, name)
    index, width, lines = _csv_lines(name, text, TELEMETRY_COLUMNS)
    # A row of another width is a cut-short (or corrupt) line.
    commas = width - 1
    for k, line in enumerate(lines):
        if line.count(",") != commas:
            raise RunError(name, f"line {k + 2}: {line.count(',') + 1} fields, expected {width} "
                                 "(a cut-short or corrupt line)")
    cols = [index[c] for c in TELEMETRY_COLUMNS]
    try:
        data = np.loadtxt(lines, delimiter=",", usecols=cols, dtype=np.float64, ndmin=2)
    except ValueError:
        # Find the offending field ourselves for a clear message.
        for k, line in enumerate(lines):
            fields = line.split(",")
            for c, i in zip(TELEMETRY_COLUMNS, cols):
                try:
                    float(fields[i])
                except ValueError:
                    raise _bad_field(name, k + 2, c, fields[i]) from None
        raise RunError(name, "cannot be parsed as numbers") from None
    return {c: data[:, j] for j, c in enumerate(TELEMETRY_COLUMNS)}


EDGE_LIST_RE = re.compile(r"(?:\d+-\d+:[^;:,\s]+)(?:;\d+-\d+:[^;:,\s]+)*")
WEIGHT_RE = re.compile(r":[^;]*")


def parse_edges(s):
    """[(a, b, weight)] of an edge_list checked by read_graph ("a-b:w;a-b:w")."""
    out = []
    for item in s.split(";") if s else ():
        pair, w = item.split(":")
        a, b = pair.split("-")
        out.append((int(a), int(b), float(w)))
    return out


def read_graph(run_dir):
    name = run_dir_names.GRAPH
    text = _read_text(run_dir, name)
    index, width, lines = _csv_lines(name, text, GRAPH_COLUMNS)
    rows = []
    for k, fields in enumerate(csv.reader(lines)):
        lineno = k + 2
        if len(fields) != width:
            raise RunError(name, f"line {lineno}: {len(fields)} fields, expected {width} "
                                 "(a cut-short or corrupt line)")
        row = {}
        for c in GRAPH_COLUMNS[:-1]:
            v = fields[index[c]]
            try:
                row[c] = float(v)
            except ValueError:
                raise _bad_field(name, lineno, c, v) from None
        # The edge list is checked here but parsed only for the snapshots drawn (a 64-agent run
        # has ~2000 edges a row); "pairs" (the list without weights) tells when the set changes.
        el = fields[index["edge_list"]].strip()
        if el and not EDGE_LIST_RE.fullmatch(el):
            raise RunError(name, f"line {lineno}: bad edge_list '{el[:40]}' "
                                 "(expected a-b:weight;a-b:weight...)")
        try:
            if el:
                float(el[el.rindex(":") + 1:])
        except ValueError:
            raise RunError(name, f"line {lineno}: bad weight at the end of edge_list") from None
        row["edge_list"] = el
        row["pairs"] = WEIGHT_RE.sub("", el)
        rows.append(row)
    rows.sort(key=lambda r: r["t_s"])  # stable: the initial graph (t 0) may be written late
    return rows


def read_events(run_dir):
    name = run_dir_names.EVENTS
    text = _read_text(run_dir, name)
    index, width, lines = _csv_lines(name, text, EVENT_COLUMNS, allow_no_rows=True)
    events = []
    for k, fields in enumerate(csv.reader(lines)):
        lineno = k + 2
        if len(fields) < width:
            raise RunError(name, f"line {lineno}: {len(fields)} fields, expected {width} "
                                 "(a cut-short or corrupt line)")
        try:
            t = float(fields[index["t_s"]])
        except ValueError:
            raise _bad_field(name, lineno, "t_s", fields[index["t_s"]]) from None
        try:
            agent = int(fields[index["agent"]])
        except ValueError:
            raise _bad_field(name, lineno, "agent", fields[index["agent"]]) from None
        events.append({"t_s": t, "kind": fields[index["kind"]].strip(), "agent": agent,
                       "detail": fields[index["detail"]]})
    return events


def _vec3(summary, key):
    v = summary.get(key)
    if (not isinstance(v, list) or len(v) != 3
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
        raise RunError(run_dir_names.SUMMARY, f"'{key}' is not a list of 3 numbers")
    return [float(x) for x in v]


def read_summary(run_dir):
    name = run_dir_names.SUMMARY
    text = _read_text(run_dir, name)
    try:
        s = json.loads(text)
    except json.JSONDecodeError as e:
        raise RunError(name, f"not valid JSON ({e.msg} at line {e.lineno} column {e.colno}): "
                             "a half-written file?") from None
    if not isinstance(s, dict):
        raise RunError(name, "not a JSON object")
    missing = [k for k in SUMMARY_KEYS if k not in s]
    if missing:
        raise RunError(name, "lacks " + ", ".join(f"'{k}'" for k in missing))
    s["initial_average"] = _vec3(s, "initial_average")
    s["final_consensus_mean"] = _vec3(s, "final_consensus_mean")
    return s


def read_scenario(run_dir, swarm):
    """The scenario as run (scenario.txtpb, optional) read by `swarm inspect --json` (see
    binaries.inspect): its inspection, or None when the run directory has no scenario."""
    if _read_text(run_dir, run_dir_names.SCENARIO, required=False) is None:
        return None
    path = os.path.join(run_dir, run_dir_names.SCENARIO)
    try:
        return binaries.inspect(swarm, path)
    except binaries.BinaryError as e:
        raise RunError(run_dir_names.SCENARIO, e.what if e.where == path else str(e)) from None


# ---------------------------------------------------------------------------------------------
# Preparing the data


class Track:
    """One agent's running samples, time-sorted, decimated, with NaN rows at gaps."""

    def __init__(self, agent_id, t, cols):
        self.id = agent_id
        self.t = t
        self.cols = cols


def build_tracks(tel, np):
    running = tel["phase"] == PHASE_RUNNING
    ids_all = tel["id"][running]
    if ids_all.size == 0:
        return [], False
    order = np.lexsort((tel["seq"][running], tel["stamp_s"][running], ids_all))
    cols = {c: tel[c][running][order] for c in TELEMETRY_COLUMNS}
    ids = cols["id"]
    quad = bool(np.any(cols["mode"] == MODE_QUADCOPTER))
    uniq, starts = np.unique(ids, return_index=True)
    ends = list(starts[1:]) + [ids.size]
    tracks = []
    for aid, a, b in zip(uniq, starts, ends):
        t = cols["stamp_s"][a:b]
        stride = max(1, int(math.ceil((b - a) / MAX_POINTS_PER_AGENT)))
        sel = np.arange(0, b - a, stride)
        if sel[-1] != b - a - 1:
            sel = np.append(sel, b - a - 1)  # keep the last sample
        ts = t[sel]
        dt = np.diff(ts)
        # A gap (a kill, a cut from the recorder, lost samples) breaks the line.
        typical = float(np.median(np.diff(t))) if t.size > 1 else 0.02
        gap = max(0.5, 25.0 * typical * stride)
        breaks = np.nonzero(dt > gap)[0] + 1
        track_cols = {}
        for c in ("qx", "qy", "qz", "px", "py", "pz", "qw", "qxr", "qyr", "qzr",
                  "w1", "w2", "w3", "w4"):
            track_cols[c] = np.insert(cols[c][a:b][sel], breaks, np.nan)
        ts = np.insert(ts, breaks, np.nan)
        tracks.append(Track(int(aid), ts, track_cols))
        # Full-rate arrays for position look-ups (graph snapshots).
        tracks[-1].t_full = t
        tracks[-1].p_full = (cols["px"][a:b], cols["py"][a:b])
        tracks[-1].q_full = np.column_stack((cols["qx"][a:b], cols["qy"][a:b], cols["qz"][a:b]))
    return tracks, quad


def fault_windows(events, t_end):
    """(windows, marks): windows = [(kind, t0, t1, label)], marks = [(t, kind, label)]."""
    windows, marks = [], []
    open_ = {}  # (kind, key) -> [t0, label]

    def key_of(kind, e):
        d = e["detail"]
        if kind == "cut":
            m = re.search(r"link (\S+)", d)
            return m.group(1) if m else d
        if kind == "partition":
            m = re.search(r"\{[^}]*\}", d)
            return m.group(0) if m else d
        if kind == "loss":
            return d
        return e["agent"]

    def close(kind, key, t1):
        stack = open_.get((kind, key))
        if not stack:  # an end without its start: close the oldest open one of that kind
            cands = [k for k, v in open_.items() if k[0] == kind and v]
            if not cands:
                return
            stack = open_[cands[0]]
        t0, label = stack.pop(0)
        windows.append((kind, t0, t1, label))

    starts = {"cut": "cut", "partition": "partition", "loss": "loss", "kill": "kill"}
    ends = {"cut_end": "cut", "heal": "partition", "loss_end": "loss", "restart": "kill"}
    for e in sorted(events, key=lambda e: e["t_s"]):
        k = e["kind"]
        if k in starts:
            label = (f"kill {e['agent']}" if k == "kill" else
                     e["detail"] if k != "cut" else f"cut {key_of(k, e)}")
            open_.setdefault((k, key_of(k, e)), []).append([e["t_s"], label])
            if k == "kill":
                marks.append((e["t_s"], "kill", f"kill {e['agent']}"))
        elif k in ends:
            kind = ends[k]
            close(kind, key_of(kind, e), e["t_s"])
            if k == "restart":
                marks.append((e["t_s"], "restart", f"restart {e['agent']}"))
        elif k == "late_join":
            marks.append((e["t_s"], "late_join", f"late join {e['agent']}"))
    for (kind, _), stack in sorted(open_.items(), key=lambda kv: str(kv[0])):
        for t0, label in stack:  # never ended: until the end of the run
            windows.append((kind, t0, max(t_end, t0), label))
    windows.sort(key=lambda w: (w[1], w[0]))
    return windows, marks


def load_run(run_dir, np, swarm):
    """Every file of the run directory, checked; `swarm` is the binary that reads its scenario."""
    if not os.path.isdir(run_dir):
        raise RunError("", "no such run directory" if not os.path.exists(run_dir)
                       else "not a directory")
    summary = read_summary(run_dir)
    inspection = read_scenario(run_dir, swarm)
    scenario = inspection["resolved"] if inspection else {}
    tel = read_telemetry(run_dir, np)
    graph = read_graph(run_dir)
    events = read_events(run_dir)
    tracks, quad = build_tracks(tel, np)
    name = summary.get("scenario") or scenario.get("name") or os.path.basename(
        os.path.normpath(run_dir))
    seed = summary["seed"]
    mode = "quadcopter" if quad else (summary.get("mode") or "particle")
    if mode == "quadcopter" and not quad:
        quad = True
    t_ends = [r["t_s"] for r in graph]
    t_ends += [float(np.nanmax(tr.t)) for tr in tracks if tr.t.size]
    dur = summary.get("duration_s")
    if isinstance(dur, (int, float)) and math.isfinite(dur):
        t_ends.append(float(dur))
    t_end = max(t_ends + [1e-3])
    windows, marks = fault_windows(events, t_end)
    return {"summary": summary, "tracks": tracks, "graph": graph, "events": events,
            "quad": quad, "name": name, "seed": seed, "mode": mode, "t_end": t_end,
            "windows": windows, "marks": marks,
            "tolerance_m": scenario.get("convergence", {}).get("tolerance_m"),
            "inspection": inspection, "scenario": scenario}
