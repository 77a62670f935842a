"""The C++ binaries the Python asks instead of restating them: `swarm inspect --json` reads a
scenario as a run flies it (every default resolved) and its initial graph."""

import json
import subprocess


class BinaryError(Exception):
    """A binary that could not run or failed; `where` is the file (or binary) it is about."""

    def __init__(self, where, what):
        super().__init__(f"{where}: {what}")
        self.where = where
        self.what = what


def inspect(swarm, scenario_path):
    """`swarm inspect SCENARIO --json` as a dict: the agents, initial edges, Laplacian, eigenvalues
    and `resolved`, the scenario with every default written back (protobuf JSON with the proto's
    field names: `resolved["topology"]["policy"] == "FIXED"`; 64-bit integers are strings)."""
    try:
        r = subprocess.run([swarm, "inspect", scenario_path, "--json"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
    except OSError as e:
        raise BinaryError(swarm, f"cannot run ({e.strerror})") from None
    if r.returncode != 0:
        raise BinaryError(scenario_path,
                          f"swarm inspect exited {r.returncode}: {r.stderr.strip()}")
    try:
        return json.loads(r.stdout)
    except json.JSONDecodeError:
        raise BinaryError(scenario_path, "swarm inspect printed no JSON") from None
