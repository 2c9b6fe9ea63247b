"""Tables, plots and a report from a psweep results folder (`make plots RESULTS=DIR`).

Reads DIR/runs.csv (and DIR/meta.json if present) and writes
  DIR/speedup.csv        one row per configuration: minimum wall time, speed-up, efficiency,
                         serial fraction, cost per unit of work
  DIR/weak.csv           weak-scaling series (N grows with T), when the sweep has any
  DIR/plots/*.png, *.svg speed-up, efficiency and wall time against threads, scaling fits,
                         context switches, stage breakdown
  DIR/report.md          provenance, failed runs, optimal-T tables, plots embedded
  DIR/report.html        the same as one self-contained page: figures inside, tooltips naming
                         each point's configuration, sortable tables
Exit status: 0 done, 2 bad input (missing folder or columns, no successful T=1 run).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path


from analysis.common.load import InputError, load_results, require_usable


def parse_args(argv):
    parser = argparse.ArgumentParser(
        description="Speed-up tables, plots and report.md from a psweep results folder.",
        epilog="Writes DIR/speedup.csv, DIR/plots/*.png|svg, DIR/report.md and DIR/report.html. "
               "Exit 2 on bad input (missing folder, missing columns, no T=1 baseline).")
    parser.add_argument("results", metavar="DIR", help="results folder holding runs.csv "
                        "(and meta.json), e.g. results/threads")
    parser.add_argument("--no-svg", action="store_true",
                        help="write PNG only (faster; SVG is for papers and slides)")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    try:
        results = load_results(args.results)
        require_usable(results)
    except InputError as err:
        print(f"plots: error: {err}", file=sys.stderr)
        return 2
    # Imported after validation: matplotlib costs a second, bad input should not wait for it.
    from analysis.common import figures
    from analysis.plots.gallery import draw_all
    from analysis.plots.fits import fit_table
    from analysis.plots.report import write_report
    from analysis.common.csv_out import write_csv
    from analysis.plots.speedup import speedup_table
    from analysis.plots.ranks import ranks_table
    from analysis.plots.weak import weak_table

    if args.no_svg:
        figures.FORMATS = ("png",)
    directory = Path(args.results)
    from analysis.plots.ceilings import Ceilings
    table = speedup_table(results.runs, results.cores, results.declaration, results.programs,
                          Ceilings.from_meta(results.meta))
    write_csv(table, directory / "speedup.csv")
    weak = weak_table(table, results.cores)
    if not weak.empty:
        write_csv(weak, directory / "weak.csv")
    ranks = ranks_table(table, results.runs, results.declaration)
    if not ranks.empty:
        write_csv(ranks, directory / "ranks.csv")
    drawn = draw_all(results, table, directory / "plots")
    fits = fit_table(table)
    write_report(directory / "report.md", results, table, fits, drawn)
    print(f"plots: wrote {directory / 'speedup.csv'}, {len(drawn)} plots in "
          f"{directory / 'plots'}, {directory / 'report.md'} and {directory / 'report.html'}",
          file=sys.stderr)
    return 0

