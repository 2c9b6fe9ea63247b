"""The scoreboard of a psweep results folder (`make scoreboard RESULTS=DIR`): per scene, every
external program and engine with its `psim check` verdict, first violation, time at T=1, best time
and its T, speed-up, and its speed against the fastest exact engine (board.py), sorted by verdict,
then speed. Writes DIR/scoreboard.csv, DIR/scoreboard.md and DIR/scoreboard.html (sortable)
and prints the tables.

Usage: /usr/bin/python3 -m analysis scoreboard DIR
Exit status: 0, 2 bad input (missing folder or columns).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from analysis.common.csv_out import write_csv
from analysis.common.load import InputError, load_results
from analysis.common.page import write_pages
from analysis.scoreboard.board import scoreboard, scoreboard_markdown


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description="Programs and engines of a results folder, judged and timed.",
        epilog="Writes DIR/scoreboard.csv, .md and .html; exit 2 on bad input.")
    parser.add_argument("results", metavar="DIR", help="results folder holding runs.csv and "
                        "meta.json, e.g. results/programs_example")
    args = parser.parse_args(argv)
    try:
        results = load_results(args.results)
    except InputError as err:
        print(f"scoreboard: error: {err}", file=sys.stderr)
        return 2
    board = scoreboard(results.runs, results.programs, results.declaration)
    path = Path(args.results) / "scoreboard.csv"
    write_csv(board, path)
    text = scoreboard_markdown(board)
    page = write_pages(path.with_suffix(".md"), f"# Scoreboard: {Path(args.results).name}\n\n{text}")
    print(text, end="")
    print(f"scoreboard: wrote {path}, {path.with_suffix('.md')} and {page}", file=sys.stderr)
    return 0
