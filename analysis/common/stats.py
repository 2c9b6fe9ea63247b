"""Per-configuration aggregates over repetitions: pure functions over the runs frame.

A configuration is CONFIG_PARAMS plus the thread count T. Only `ok` runs enter the statistics;
the minimum is the statistic of record (the least-disturbed run on a noisy machine, as Box2D's
and google/benchmark's runners report it), median and maximum show the spread.
"""
from __future__ import annotations

import pandas as pd

from analysis.load import CONFIG_PARAMS

RUN_KEYS = CONFIG_PARAMS + ["T"]


def group_runs(runs: pd.DataFrame, keys: list[str] = RUN_KEYS):
    # dropna=False: G, speed_min/max and scene_file are legitimately empty and must stay keys.
    return runs.groupby(keys, dropna=False, sort=True)


def aggregate(runs: pd.DataFrame, column: str, keys: list[str] = RUN_KEYS) -> pd.DataFrame:
    """min / median / max of `column` over the ok runs of each configuration. Configurations
    whose ok runs all left the column empty (e.g. hardware counters on a VM) are dropped."""
    ok = runs[(runs["status"] == "ok") & runs[column].notna()]
    if ok.empty:
        return pd.DataFrame(columns=keys + [f"{column}_min", f"{column}_median",
                                            f"{column}_max", "reps"])
    grouped = group_runs(ok, keys)[column]
    table = grouped.agg(["min", "median", "max", "count"]).reset_index()
    return table.rename(columns={"min": f"{column}_min", "median": f"{column}_median",
                                 "max": f"{column}_max", "count": "reps"})


def failures(runs: pd.DataFrame, keys: list[str] = RUN_KEYS) -> pd.DataFrame:
    """Number of non-ok repetitions per configuration (0 where all succeeded)."""
    flagged = runs.assign(failed=(runs["status"] != "ok").astype(int))
    return group_runs(flagged, keys)["failed"].sum().reset_index()


def varying(table: pd.DataFrame, columns: list[str]) -> list[str]:
    """The columns that take more than one value (NaN counts as a value): what a legend or a
    table must show; constant columns belong in a title or the provenance instead."""
    return [c for c in columns if c in table.columns and table[c].nunique(dropna=False) > 1]


def record_runs(runs: pd.DataFrame, keys: list[str] = RUN_KEYS) -> pd.DataFrame:
    """Per configuration the ok run with the minimum wall time: the run whose numbers the tables
    report, so that its stage times add up against its own wall time (medians of separate
    columns would not)."""
    ok = runs[(runs["status"] == "ok") & runs["wall_s"].notna()]
    if ok.empty:
        return ok
    best = group_runs(ok, keys)["wall_s"].idxmin()
    return ok.loc[best.values].reset_index(drop=True)
