"""The names of the files in a run directory, spelled once for the Python.

`swarm run` writes scenario.txtpb and the supervisor's Recorder (common/record/) the rest; what each
holds: docs/architecture.md, "The run directory". `swarm paper` keeps one run directory per
rendezvous scenario (named by the scenario file's stem) and the section 4 maneuvers side by side.
"""

# One run directory.
SUMMARY = "summary.json"
TELEMETRY = "telemetry.csv"
GRAPH = "graph.csv"
EVENTS = "events.csv"
SCENARIO = "scenario.txtpb"  # the scenario as run: read through `swarm inspect --json`
RECORDS = "records.pb"  # the samples, graph and events as Protobuf (nothing here reads it)
MCAP = "run.mcap"  # the same and a 3D scene as MCAP, for Foxglove or Lichtblick (nor this)
PLOTS = "plots"  # not written by the run: where `swarm plot` puts its figures by default
PROCESSES = "processes.csv"  # role,id,pid of every process the launcher started
AGENT_STATS = "agent-N.stats"  # N: the agent's id (agent_file)

# `swarm paper`'s runs: RUNS/<scenario stem>/ (run directories) and RUNS/maneuvers/, which
# common/sim/paper_maneuvers.cpp writes.
MANEUVERS = "maneuvers"
SINGLE_AGENT = "single_agent.csv"
RENDEZVOUS_DYNAMICS = "rendezvous_dynamics.csv"
SEGMENTS = "segments.csv"


def agent_file(pattern, agent_id):
    """An agent's file from its pattern: agent_file(AGENT_STATS, 3) is "agent-3.stats"."""
    return pattern.replace("N", str(agent_id), 1)
