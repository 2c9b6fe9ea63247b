"""Per-configuration aggregates over repetitions: pure functions over the runs frame.

A configuration is CONFIG_PARAMS plus the thread count T. Only `ok` runs enter the statistics;
the minimum is the statistic of record (the least-disturbed run on a noisy machine, as Box2D's
and google/benchmark's runners report it), median and maximum show the spread.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from analysis.common.load import CONFIG_PARAMS

RUN_KEYS = CONFIG_PARAMS + ["T"]

# google/benchmark's defaults: 5 repetitions before the U test is trusted, alpha 0.05.
MIN_REPS_FOR_U = 5
ALPHA = 0.05
# The verdict where fewer repetitions than the U test needs cannot separate two samples.
TOO_FEW = "not enough repetitions to tell"


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


def compare_samples(a, b, alpha: float = ALPHA) -> tuple[str, float, str]:
    """Judge two samples of wall times: returns (test, p_value, verdict).

    test is "U test" (both sides have >= MIN_REPS_FOR_U values), "ranges" (2 to 4 each) or
    "none" (a single value: no spread to compare against). verdict is "slower" / "faster" (b
    against a, beyond the spread), "same" (the U test found no difference) or TOO_FEW: with
    ranges, a difference is beyond the spread only when the gap between the two min-max ranges
    is wider than either range (two back-to-back sweeps of 3 repetitions often miss each other
    by a percent or two: noise, not a regression); one value has no spread at all. p_value is
    NaN unless the U test ran."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if min(len(a), len(b)) >= MIN_REPS_FOR_U:
        from scipy.stats import mannwhitneyu
        p = float(mannwhitneyu(a, b, alternative="two-sided").pvalue)
        if p >= alpha:
            return "U test", p, "same"
        # The U test says the distributions differ; the medians say which way.
        return "U test", p, "slower" if np.median(b) > np.median(a) else "faster"
    if min(len(a), len(b)) >= 2:
        spread = max(np.ptp(a), np.ptp(b))
        if b.min() - a.max() > spread:
            return "ranges", math.nan, "slower"
        if a.min() - b.max() > spread:
            return "ranges", math.nan, "faster"
        return "ranges", math.nan, TOO_FEW
    return "none", math.nan, TOO_FEW
