"""quadswarm's Python: the figures and reports drawn from run records.

`swarm plot` runs `python3 -m qswarm.plot`, `swarm paper` `python3 -m qswarm.paper` and so on, with
PYTHONPATH at the copy of this package the build keeps beside the `swarm` binary (bin/python/).

  run_dir        the run directory's file names
  report         one run's numbers for scripts (python3 -m qswarm.report RUN_DIR FIELD...)
  record         reading and checking one run directory
  binaries       what the C++ binaries answer: a scenario as run (`swarm inspect --json`) and its
                 agreement law in lockstep (swarm-preview); nothing here restates either
  drawing        matplotlib on Agg, figures saved byte for byte the same
  plot           `swarm plot`: a run's figures
  paper          `swarm paper`: flies and reads the paper's runs, then
  paper_numbers  the paper's printed numbers and ours,
  paper_figures  its figures,
  paper_report   and report.md
  resilience     `swarm resilience`: the three laws under one lying insider (swarm-preview --liar)
"""
