"""One run directory's numbers for scripts (the benchmarks, the soak), so that no script spells
the record's file names or reads its JSON with grep:

  python3 -m qswarm.report RUN_DIR FIELD [FIELD ...]

prints each field's value, tab-separated, on one line (a missing value prints "-"). Fields:

  a summary.json path       converged, end_reason, messages.age_p50_ms, faults.injected.loss
  stats.KEY.HOW             KEY of every agent-N.stats (cpu_s, wall_s, steps, overruns,
                            discovery_s, max_rss_kb, received, dropped, ...), HOW one of sum,
                            mean, median, min, max
  stats.count               how many agents wrote their stats
  telemetry.rows            rows of telemetry.csv
  events.ended              "yes" when events.csv has the run's end event
  files.missing             the run's files that are absent or empty, comma-separated ("-": none)
  pids                      role:id:pid of every process the launcher started, comma-separated
  cpu_per_agent_pct         100 x total agent CPU / total agent running wall time
  flight_cpu_per_agent_pct  the same without start-up and discovery: CPU from each agent's
                            barrier release to its end
  flight_wakeups_per_s      times an agent's threads blocked and woke again, per agent and
                            second of running (voluntary context switches, all threads)
  start_spread_s            how far apart the agents left their start barriers: the last
                            agent's start less the first's (system clock)
  late_ticks_pct            100 x late ticks / ticks
  delivered_per_s           samples the agents accepted, per second of running (all agents)
  cpu_us_per_delivered      agent CPU per accepted sample [us]

Exit status 2 when RUN_DIR has no summary.json, or a field is unknown.
"""

import csv
import glob
import json
import os
import statistics
import sys

from qswarm import run_dir as names

HOWS = {"sum": sum, "mean": statistics.fmean, "median": statistics.median, "min": min, "max": max}


def agent_stats(run_dir):
    """{key: [value per agent]} from every agent-N.stats ("key value" lines)."""
    out = {}
    pattern = os.path.join(run_dir, names.AGENT_STATS.replace("N", "*"))
    for path in sorted(glob.glob(pattern)):
        with open(path, encoding="utf-8") as f:
            for line in f:
                parts = line.split()
                if len(parts) == 2:
                    try:
                        out.setdefault(parts[0], []).append(float(parts[1]))
                    except ValueError:
                        pass
    return out


def summary_value(summary, path):
    v = summary
    for part in path.split("."):
        if not isinstance(v, dict) or part not in v:
            return None
        v = v[part]
    return v


def ratio(num, den, scale=1.0):
    return None if not den else scale * num / den


def field(run_dir, summary, stats, name):
    if name == "stats.count":
        return len(stats.get("cpu_s", []))
    if name.startswith("stats."):
        parts = name.split(".")
        if len(parts) != 3 or parts[2] not in HOWS:
            raise KeyError(name)
        values = stats.get(parts[1])
        return HOWS[parts[2]](values) if values else None
    total = {k: sum(v) for k, v in stats.items()}
    if name == "cpu_per_agent_pct":
        return ratio(total.get("cpu_s", 0.0), total.get("wall_s", 0.0), 100.0)
    if name in ("flight_cpu_per_agent_pct", "flight_wakeups_per_s"):
        key, scale = (("flight_cpu_s", 100.0) if name == "flight_cpu_per_agent_pct"
                      else ("flight_voluntary_switches", 1.0))
        # An agent that never ran has no flight entries and a running wall time of 0; a build
        # older than these entries has none at all.
        return ratio(total[key], total.get("wall_s", 0.0), scale) if key in total else None
    if name == "start_spread_s":
        starts = stats.get("started_epoch_s", [])
        return max(starts) - min(starts) if starts else None
    if name == "late_ticks_pct":
        return ratio(total.get("overruns", 0.0), total.get("steps", 0.0), 100.0)
    if name == "delivered_per_s":
        walls = stats.get("wall_s", [])
        return ratio(total.get("received", 0.0), statistics.fmean(walls) if walls else 0.0)
    if name == "cpu_us_per_delivered":
        return ratio(total.get("cpu_s", 0.0), total.get("received", 0.0), 1e6)
    if name == "telemetry.rows":
        try:
            with open(os.path.join(run_dir, names.TELEMETRY), encoding="utf-8") as f:
                return max(0, sum(1 for _ in f) - 1)
        except OSError:
            return None
    if name == "events.ended":
        try:
            with open(os.path.join(run_dir, names.EVENTS), encoding="utf-8") as f:
                return "yes" if any(r.get("kind") == "end" for r in csv.DictReader(f)) else "no"
        except OSError:
            return "no"
    if name == "files.missing":
        wanted = [names.SUMMARY, names.TELEMETRY, names.GRAPH, names.EVENTS, names.RECORDS,
                  names.SCENARIO, names.PROCESSES]
        missing = [n for n in wanted if not os.path.isfile(os.path.join(run_dir, n))
                   or os.path.getsize(os.path.join(run_dir, n)) == 0]
        return ",".join(missing) if missing else None
    if name == "pids":
        try:
            with open(os.path.join(run_dir, names.PROCESSES), encoding="utf-8") as f:
                return ",".join(f"{r['role']}:{r['id']}:{r['pid']}" for r in csv.DictReader(f))
        except (OSError, KeyError):
            return None
    if summary is not None:
        v = summary_value(summary, name)
        if v is not None or "." in name or name in summary:
            return v
    raise KeyError(name)


def text(v):
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, dict)):
        return json.dumps(v, separators=(",", ":"))
    return str(v)


def main(argv):
    if len(argv) < 2 or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    run_dir, fields = argv[0], argv[1:]
    path = os.path.join(run_dir, names.SUMMARY)
    try:
        with open(path, encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        print(f"qswarm.report: {path}: {e}", file=sys.stderr)
        return 2
    stats = agent_stats(run_dir)
    out = []
    for name in fields:
        try:
            out.append(text(field(run_dir, summary, stats, name)))
        except KeyError:
            print(f"qswarm.report: unknown field {name!r} (see --help)", file=sys.stderr)
            return 2
    print("\t".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
