"""Drawing for the parallel-performance views: sweep comparison ratios, the Karp-Flatt serial
fraction, weak scaling and cost per unit of work. Same contract as figures.py (tables in, files
out, None when there is nothing to draw) and the same helpers, so these plots read like the rest.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from analysis.figures import (MAX_SERIES, context, draw_series, mark_cores,
                              outside_legend, plt, readable_log, save, series_columns,
                              series_label, thread_axis)

VERDICT_COLOURS = {"slower": "C3", "faster": "C2", "same": "0.6", "unknown": "0.85"}


def plot_ratios(table: pd.DataFrame, label_columns: list[str], stem: Path, a_name: str,
                b_name: str) -> Path | None:
    """One horizontal bar per configuration from 1 to its ratio B / A on a log axis (2x slower
    and 2x faster look alike), coloured by the verdict."""
    rows = table.dropna(subset=["ratio"]).reset_index(drop=True)
    if rows.empty:
        return None
    height = min(30.0, 1.6 + 0.28 * len(rows))
    fig, ax = plt.subplots(figsize=(8.5, height))
    y = np.arange(len(rows))
    colours = [VERDICT_COLOURS.get(v, "0.6") for v in rows["verdict"]]
    ax.barh(y, rows["ratio"] - 1, left=1, color=colours, height=0.7)
    ax.axvline(1, color="0.2", linewidth=1)
    ax.set_yticks(y)
    ax.set_yticklabels([series_label(row, label_columns) for _, row in rows.iterrows()],
                       fontsize=7 if len(rows) > 20 else 9)
    ax.invert_yaxis()
    spread = max(float(np.abs(np.log(rows["ratio"])).max()), np.log(1.1))
    ax.set_xlim(np.exp(-1.15 * spread), np.exp(1.15 * spread))
    ax.set_xlabel(f"wall time ratio {b_name} / {a_name} (min over repetitions)")
    readable_log(ax, "x")
    present = [v for v in VERDICT_COLOURS if v in set(rows["verdict"])]
    handles = [plt.Rectangle((0, 0), 1, 1, color=VERDICT_COLOURS[v]) for v in present]
    ax.legend(handles, present, title="beyond the spread?", loc="upper left",
              bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    ax.set_title(f"{b_name} against {a_name}: right of 1 is slower")
    return save(fig, stem)


def plot_karp_flatt(table: pd.DataFrame, cores: int | None, stem: Path) -> Path | None:
    """Karp-Flatt e against T (T > 1), one line per configuration, with each configuration's
    Amdahl f as a dashed level of the same colour: where e leaves it, Amdahl's law stops
    describing the code. Needs two thread counts above 1: a single point shows no trend."""
    rated = table.dropna(subset=["karp_flatt"])
    if rated["T"].nunique() < 2:
        return None
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    columns = series_columns(rated)
    draw_series(ax, rated, "karp_flatt", columns)
    by = columns[0] if len(columns) == 1 else columns
    groups = list(rated.groupby(by, dropna=False, sort=True)) if columns else [((), rated)]
    ts = sorted(rated["T"].unique())
    dashed = False
    for i, (_, group) in enumerate(groups[:MAX_SERIES]):
        f = group["amdahl_f"].iloc[0]
        if np.isfinite(f):
            ax.hlines(f, ts[0], ts[-1], colors=f"C{i % 10}", linestyles="--", linewidth=1)
            dashed = True
    mark_cores(ax, cores, max(ts))
    thread_axis(ax, ts)
    ax.axhline(0, color="0.2", linewidth=0.8)
    ax.set_ylabel("Karp-Flatt serial fraction e")
    fitted_on = f" on T <= {cores}" if cores else ""
    fit_note = f"; dashed: Amdahl f fitted{fitted_on}" if dashed else ""
    ax.set_title(f"Serial fraction against threads (rising: overhead grows with T"
                 f"{fit_note})\n{context(rated, columns)}")
    outside_legend(ax)
    return save(fig, stem)
