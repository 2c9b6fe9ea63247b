"""particle-lab analysis: tables, plots and a report from a psweep results folder.

Layout (computing apart from drawing, so the numbers are testable without a display):
  load.py      read runs.csv / meta.json, validate at the boundary (InputError -> exit 2)
  stats.py     per-configuration aggregates (min / median / max over ok repetitions)
  speedup.py   speed-up, efficiency, speed-up over sequential brute
  tables.py    optimal thread count and peak speed-up, failures, state-hash agreement
  fits.py      power-law fits for one-at-a-time scaling sweeps
  figures.py   matplotlib drawing only (Agg backend)
  report.py    report.md
  plots.py     command line: `make plots RESULTS=DIR`
  trajectory.py, animate.py   psim print-mode output -> GIF (`make animate`)
  targets.py   the speed targets per scene: `make targets`, `make million`
"""
