"""Robustness to a busy neighbour and to more threads than cores, from a `neighbour` sweep
(`make noise`, configs/noise.json).

Reads DIR/runs.csv and writes
  DIR/noise.csv        per engine, neighbour and T: minimum, median and maximum wall time; the
                       minimum against T=1 and T=2 of the same engine and neighbour; the worst
                       repetition against the quiet minimum of the same engine and T
  DIR/plots/noise.png  wall time against T, quiet and busy, the spread of the repetitions shaded
Exit status: 0 done, 2 bad input (missing folder or columns, no quiet runs).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd


from analysis.common.load import InputError, load_results

KEYS = ["engine", "neighbour", "T"]


def noise_table(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per engine, neighbour and T over the successful runs (computing only)."""
    ok = runs[runs["status"] == "ok"].copy()
    ok["neighbour"] = ok["neighbour"].fillna("none")
    if not (ok["neighbour"] == "none").any():
        raise InputError("no successful quiet run (neighbour none): nothing to compare with")
    table = (ok.groupby(KEYS)["wall_s"].agg(wall_s_min="min", wall_s_median="median",
                                            wall_s_max="max", reps="count")
             .reset_index())
    table["T"] = table["T"].astype(int)
    by = table.set_index(KEYS)["wall_s_min"]

    def ratio_to(row, key, t=None, neighbour=None):
        ref = (row["engine"], neighbour or row["neighbour"], t if t is not None else row["T"])
        return row[key] / by[ref] if ref in by.index else float("nan")

    table["vs_T1"] = table.apply(lambda r: ratio_to(r, "wall_s_min", t=1), axis=1)
    table["vs_T2"] = table.apply(lambda r: ratio_to(r, "wall_s_min", t=2), axis=1)
    table["worst_vs_quiet_min"] = table.apply(
        lambda r: ratio_to(r, "wall_s_max", neighbour="none"), axis=1)
    return table


def draw(table: pd.DataFrame, path: Path) -> Path:
    from analysis.common import figures
    plt = figures.plt
    engines = list(dict.fromkeys(table["engine"]))
    fig, axes = plt.subplots(1, len(engines), figsize=(5 * len(engines), 4), squeeze=False)
    for ax, engine in zip(axes[0], engines):
        for neighbour, style in (("none", "-o"), ("busy", "--s")):
            rows = table[(table["engine"] == engine) & (table["neighbour"] == neighbour)]
            if rows.empty:
                continue
            rows = rows.sort_values("T")
            line, = ax.plot(rows["T"], rows["wall_s_min"], style,
                            label=f"{neighbour} (min; shaded: min to max)")
            ax.fill_between(rows["T"], rows["wall_s_min"], rows["wall_s_max"],
                            color=line.get_color(), alpha=0.2)
        ax.set_title(engine)
        ax.set_xlabel("threads T")
        ax.set_ylabel("wall time (s)")
        ax.set_ylim(bottom=0)
        ax.legend()
    fig.suptitle("Quiet machine against one busy neighbour (a spinning process on one core)")
    return figures.save(fig, path.with_suffix(""))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", metavar="DIR", help="results folder of a neighbour sweep")
    args = parser.parse_args(argv)
    directory = Path(args.results)
    try:
        table = noise_table(load_results(directory).runs)
    except InputError as err:
        print(f"noise: error: {err}", file=sys.stderr)
        return 2
    from analysis.common.csv_out import write_csv
    write_csv(table, directory / "noise.csv")
    (directory / "plots").mkdir(exist_ok=True)
    drawn = draw(table, directory / "plots" / "noise")
    print(f"noise: wrote {directory / 'noise.csv'}, {drawn}", file=sys.stderr)
    print(table.to_string(index=False))
    return 0

