"""quadswarm's Python: the figures and reports drawn from run records.

`swarm plot` runs `python3 -m qswarm.plot` and `swarm paper` runs `python3 -m qswarm.paper`, with
PYTHONPATH at the copy of this package the build keeps beside the `swarm` binary (bin/python/).
"""
