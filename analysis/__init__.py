"""particle-lab analysis: one package, one entry point (`/usr/bin/python3 -m analysis TOOL`, see
__main__.py), one subpackage per tool, each with its command line in cli.py:

  plots/      make plots: speedup.csv, weak.csv, plots/ and report.md from a psweep results
              folder (speedup, serial, weak, cost, fits, tables: computing; figures,
              figures_hpc, gallery: drawing; report, sections: report.md)
  compare/    make compare: two results folders configuration by configuration
  accuracy/   make accuracy: error against run time, against the exact engine and theory
  stability/  make stability: stiff and extreme scenes (scenes.py) through every engine
  regress/    make regress: the suite (suite.py) against its baseline (check.py), report.py,
              changepoint.py for the history
  targets/    make targets, make million: the speed targets per scene
  noise/      make noise: quiet against one busy neighbour
  animate/    make animate: a scene as a GIF
  scoreboard/ make scoreboard: programs beside the engines, verdict first, then speed
  grade/      make grade: a folder of submissions through psweep (plan), the grade board
              over every scene (board, from the scoreboard's rows) and a report each (report)
  common/     what several tools share: load (results folders, InputError -> exit 2),
              declaration (psim's engines and metrics), stats, labels (names and number
              formats), markdown, figures (the look and save()), csv_out (the one CSV writer),
              psim (the one psim runner), trajectory (psim's printed output)

Computing stays apart from drawing, so the numbers are testable without a display.
"""
