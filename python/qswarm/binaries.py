"""The C++ binaries the Python asks instead of restating them: `swarm inspect --json` reads a
scenario as a run flies it (every default resolved) and its initial graph; swarm-preview flies its
agreement law in lockstep (the C++ oracle LockstepLaws)."""

import csv
import json
import os
import subprocess
import tempfile


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


def lockstep(preview, scenario_path, np, law="laplacian", liar=None):
    """`swarm-preview SCENARIO --law LAW --csv`: the scenario's agents flown by the bare laws in
    lockstep (every agent at every tick from the others' states of the previous tick) at its
    consensus rate, until its tolerance or duration. With `liar` ("ID:KIND", swarm-preview's
    --liar) that agent lies for the whole duration and only the honest agents are returned.
    Returns (t_s, ids, states), states being ticks x agents x 3 in the order of ids."""
    with tempfile.TemporaryDirectory(prefix="qswarm-lockstep-") as tmp:
        path = os.path.join(tmp, "lockstep.csv")
        try:
            r = subprocess.run([preview, scenario_path, "--law", law, "--csv", path]
                               + (["--liar", liar] if liar else []),
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        except OSError as e:
            raise BinaryError(preview, f"cannot run ({e.strerror})") from None
        # 1 says only that the mean moved more than 1e-6 m (or, with a liar, that the honest
        # agents did not meet inside their box): the states are still the law's.
        if r.returncode not in (0, 1):
            raise BinaryError(scenario_path,
                              f"swarm-preview exited {r.returncode}: {r.stderr.strip()}")
        with open(path, encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    ids = sorted({int(row["id"]) for row in rows})
    n = len(ids)
    if n == 0 or len(rows) % n:
        raise BinaryError(scenario_path, "swarm-preview wrote no complete ticks")
    t = np.array([float(row["t_s"]) for row in rows[::n]])
    states = np.array([[float(row[c]) for c in ("qx", "qy", "qz")] for row in rows])
    order = [ids.index(int(row["id"])) for row in rows[:n]]
    states = states.reshape(len(t), n, 3)[:, np.argsort(order), :]
    return t, ids, states
