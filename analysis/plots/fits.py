"""Power-law scaling: wall time against one parameter, the others held fixed.

The 2019 report's sequential experiments varied N, L and r one at a time and found time ~ N^2
and flat in L and r. A straight line in log-log space, log t = log a + b log x, gives the
exponent b directly; R^2 is computed in log space too, where the fit was made.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from analysis.common.load import CONFIG_PARAMS

# Parameters that are quantities (scaling against them means something). engine, seed, pin,
# scene_file are identities.
SCALING_PARAMS = ["N", "L", "r", "S", "slow_factor", "G", "T"]

# Below three distinct sizes a "fit" is just the line through two points: no exponent claimed.
MIN_POINTS = 3


@dataclass
class PowerLaw:
    prefactor: float   # a in t = a * x^b
    exponent: float    # b
    r_squared: float   # of the log-log line
    points: int

    def __call__(self, x):
        return self.prefactor * np.asarray(x, dtype=float) ** self.exponent


def fit_power_law(x, y) -> PowerLaw | None:
    """Least squares in log-log space; None when there are too few positive points."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    keep = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    x, y = x[keep], y[keep]
    if len(np.unique(x)) < MIN_POINTS:
        return None
    lx, ly = np.log(x), np.log(y)
    exponent, intercept = np.polyfit(lx, ly, 1)
    residual = ly - (intercept + exponent * lx)
    total = ((ly - ly.mean()) ** 2).sum()
    r_squared = 1.0 - (residual ** 2).sum() / total if total > 0 else 1.0
    return PowerLaw(float(np.exp(intercept)), float(exponent), float(r_squared), len(x))


def scaling_series(table: pd.DataFrame, param: str) -> list[tuple[dict, pd.DataFrame]]:
    """Split the speedup table into series along `param`: each series holds every other
    parameter (including T) fixed and has at least two values of `param`. In a one-at-a-time
    sweep this yields exactly the series through the base point; in a product sweep one series
    per combination of the other parameters (e.g. time against N for each T)."""
    others = [c for c in CONFIG_PARAMS + ["T"] if c != param]
    rated = table.dropna(subset=["wall_s_min", param])
    series = []
    for key, group in rated.groupby(others, dropna=False, sort=True):
        if group[param].nunique() >= 2:
            series.append((dict(zip(others, key)), group.sort_values(param)))
    return series


def unaffected(table: pd.DataFrame, param: str, fixed: dict) -> pd.DataFrame:
    """The runs of engines that do not read `param` (their cells of it empty: brute and cells
    against grid's G) with every other value of the series `fixed` but the engine: what the
    series is compared with, one time each whatever `param` is."""
    rated = table.dropna(subset=["wall_s_min"])
    match = rated[param].isna() & (rated["engine"] != fixed.get("engine"))
    for key, value in fixed.items():
        if key != "engine" and key in rated.columns:
            match &= rated[key].isna() if pd.isna(value) else rated[key] == value
    return rated[match]


def scaling_params(table: pd.DataFrame) -> list[str]:
    """The quantities the sweep varied apart from T (T has its own plots), in a fixed order."""
    rated = table.dropna(subset=["wall_s_min"])
    return [p for p in SCALING_PARAMS if p != "T" and rated[p].nunique() > 1]


def fit_table(table: pd.DataFrame) -> pd.DataFrame:
    """One row per scaling series with its fitted exponent (empty when too few points)."""
    rows = []
    for param in scaling_params(table):
        for fixed, group in scaling_series(table, param):
            fit = fit_power_law(group[param], group["wall_s_min"])
            rows.append(dict(fixed, parameter=param, points=len(group),
                             low=group[param].min(), high=group[param].max(),
                             exponent=fit.exponent if fit else float("nan"),
                             r_squared=fit.r_squared if fit else float("nan")))
    return pd.DataFrame(rows)
