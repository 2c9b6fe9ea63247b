"""Weak scaling: the problem grows with the threads, work per thread held constant.

A weak-scaling series is a set of configurations equal in everything but N (and whatever else
the config zipped with it, such as L) and T, with exactly one N per T, a T=1 run, and N not
constant: what a `combine: "zip"` config such as configs/weak.json produces. A product sweep
(several N at each T) has no such series; its strong-scaling numbers are in speedup.csv.

  weak_efficiency  t(1) / t(T): 1 when T threads do T times the work in the same time.
  scaled_speedup   T x weak_efficiency: Gustafson's scaled speed-up, the speed-up of the
                   T-thread problem over running it on one thread, assuming the config scaled
                   the work by exactly T (N ~ T for O(N) engines, N ~ sqrt(T) for brute).
  gustafson_serial the serial fraction s of Gustafson's law S = T - s (T - 1), least squares
                   over T up to the core count (closed form: the model is linear in s),
                   clamped to [0, 1] like Amdahl's f (1: no parallel gain at all).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from analysis.common.load import CONFIG_PARAMS

# What may change along a weak series besides T: the problem size and the box that keeps its
# density constant. Everything else (engine, S, K, G, seed, pin, ...) identifies the series.
GROWING = ["N", "L"]
SERIES_KEYS = [c for c in CONFIG_PARAMS if c not in GROWING]
WEAK_COLUMNS = SERIES_KEYS + ["T", "N", "L", "wall_s_min", "weak_efficiency", "scaled_speedup",
                              "gustafson_serial"]


def fit_gustafson(threads, scaled) -> float:
    """s in S = T - s (T - 1) by least squares over the points with T > 1; NaN without any."""
    threads = np.asarray(threads, dtype=float)
    scaled = np.asarray(scaled, dtype=float)
    keep = (threads > 1) & np.isfinite(scaled)
    if not keep.any():
        return float("nan")
    x = threads[keep] - 1.0
    return float(np.clip(((threads[keep] - scaled[keep]) * x).sum() / (x * x).sum(), 0.0, 1.0))


def weak_table(table: pd.DataFrame, cores: int | None = None) -> pd.DataFrame:
    """One row per configuration of every weak-scaling series in the speed-up table (empty
    when the sweep has none)."""
    rated = table.dropna(subset=["wall_s_min"])
    parts = []
    for _, series in rated.groupby(SERIES_KEYS, dropna=False, sort=True):
        per_t = series.groupby("T")["N"].nunique()
        if len(per_t) < 2 or (per_t > 1).any() or 1 not in per_t.index:
            continue
        if series["N"].nunique() < 2:
            continue  # N constant: strong scaling, already in speedup.csv
        series = series.sort_values("T").copy()
        t1 = series.loc[series["T"] == 1, "wall_s_min"].iloc[0]
        series["weak_efficiency"] = t1 / series["wall_s_min"]
        series["scaled_speedup"] = series["T"] * series["weak_efficiency"]
        within = series[series["T"] <= cores] if cores else series
        series["gustafson_serial"] = fit_gustafson(within["T"], within["scaled_speedup"])
        parts.append(series)
    if not parts:
        return pd.DataFrame(columns=WEAK_COLUMNS)
    return pd.concat(parts)[WEAK_COLUMNS].reset_index(drop=True)
