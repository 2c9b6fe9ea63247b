"""Serial fraction from a strong-scaling sweep: the Karp-Flatt metric and an Amdahl fit.

Amdahl's law models the normalised time of a run on T threads as t(T) / t(1) = f + (1 - f) / T,
f being the part that does not parallelise, so speed-up S(T) = 1 / (f + (1 - f) / T).

  karp_flatt  e(T) = (1/S - 1/T) / (1 - 1/T): the f that Amdahl's law would need to explain the
              speed-up measured at this T alone (Karp and Flatt, CACM 1990). A flat e across T
              means a fixed serial part; a rising e means overhead that grows with T (barriers,
              imbalance, contention); beyond the cores it mostly measures oversubscription.
              Undefined at T = 1.
  amdahl_f    one f per configuration: least squares of the normalised time 1/S against
              Amdahl's model over the measured T from 2 up to the core count. The model is linear
              in f (1/S - 1/T = f (1 - 1/T)), so the fit is closed-form: the average of e(T)
              weighted by (1 - 1/T)^2. Clamped to [0, 1], where it means something.
  amdahl_speedup  the speed-up that f predicts at this T, to set against the measured one.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from analysis.common.load import CONFIG_PARAMS

SERIAL_COLUMNS = ["karp_flatt", "amdahl_f", "amdahl_speedup"]


def karp_flatt(speedup, threads):
    speedup = np.asarray(speedup, dtype=float)
    threads = np.asarray(threads, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = (1.0 / speedup - 1.0 / threads) / (1.0 - 1.0 / threads)
    return np.where(threads > 1, e, np.nan)


def fit_amdahl(threads, speedup) -> float:
    """f by least squares over the given points with T > 1; NaN when there are none."""
    threads = np.asarray(threads, dtype=float)
    speedup = np.asarray(speedup, dtype=float)
    keep = (threads > 1) & np.isfinite(speedup) & (speedup > 0)
    if not keep.any():
        return float("nan")
    x = 1.0 - 1.0 / threads[keep]
    y = 1.0 / speedup[keep] - 1.0 / threads[keep]
    return float(np.clip((x * y).sum() / (x * x).sum(), 0.0, 1.0))


def amdahl_speedup(f, threads):
    threads = np.asarray(threads, dtype=float)
    return 1.0 / (f + (1.0 - f) / threads)


def add_serial_fraction(table: pd.DataFrame, cores: int | None) -> pd.DataFrame:
    """The speed-up table with SERIAL_COLUMNS added. Only T up to `cores` enter the fit (past
    them threads share cores, which Amdahl's law does not model); all T when cores is unknown."""
    out = table.copy()
    out["karp_flatt"] = karp_flatt(out["speedup"], out["T"])
    within = out["T"] <= cores if cores else pd.Series(True, index=out.index)
    fitted = (out[within].groupby(CONFIG_PARAMS, dropna=False, sort=False)
              .apply(lambda g: fit_amdahl(g["T"], g["speedup"]))
              .rename("amdahl_f").reset_index())
    out = out.merge(fitted, on=CONFIG_PARAMS, how="left") if len(fitted) else out.assign(
        amdahl_f=np.nan)
    out["amdahl_speedup"] = amdahl_speedup(out["amdahl_f"], out["T"])
    return out
