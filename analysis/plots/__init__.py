"""make plots: a psweep results folder as tables, plots and report.md."""
