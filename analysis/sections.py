"""report.md sections for the parallel-performance views: serial fraction, weak scaling and cost
per unit of work. Each takes computed tables and returns markdown ('' when the sweep has nothing
for it), like the sections in report.py.
"""
from __future__ import annotations

import pandas as pd

from analysis.figures import SHORT, fmt
from analysis.load import CONFIG_PARAMS
from analysis.markdown import markdown_table
from analysis.stats import varying


def serial_section(speedup: pd.DataFrame, cores: int | None) -> str:
    """Per engine: Amdahl's f and the Karp-Flatt e at every T > 1, one row per configuration."""
    rated = speedup.dropna(subset=["karp_flatt"])
    if rated.empty:
        return ""
    fitted_on = f"the thread counts from 2 to the {cores} cores" if cores else "every thread count"
    text = ("\n## Serial fraction\n\n"
            "`Amdahl f` is the serial fraction that best explains the measured times (least "
            f"squares of t(T)/t(1) = f + (1-f)/T over {fitted_on}); `e at T` is the Karp-Flatt "
            "metric (1/speed-up - 1/T) / (1 - 1/T), the serial fraction that the speed-up at "
            "that T alone implies. Equal e across T: a fixed serial part, Amdahl's law holds. "
            "e rising with T: overhead that grows with the threads (synchronisation, "
            "imbalance); past the cores, oversubscription. Both are in speedup.csv "
            "(`karp_flatt`, `amdahl_f`, `amdahl_speedup`).\n")
    for engine, group in rated.groupby("engine", sort=True):
        keys = [c for c in varying(group, CONFIG_PARAMS) if c != "engine"]
        rows = []
        by = keys if len(keys) > 1 else (keys or ["engine"])[0]  # a scalar key for one column
        for key, config in group.groupby(by, dropna=False, sort=True):
            row = dict(zip(keys, key if isinstance(key, tuple) else (key,)))
            row["Amdahl f"] = config["amdahl_f"].iloc[0]
            row.update({f"e at T={fmt(t)}": e for t, e in zip(config["T"], config["karp_flatt"])})
            rows.append(row)
        ts = [f"e at T={fmt(t)}" for t in sorted(group["T"].unique())]
        shown = pd.DataFrame(rows, columns=keys + ["Amdahl f"] + ts)
        by = " and ".join(SHORT.get(k, k) for k in keys) or "configuration"
        text += f"\n### {engine}: serial fraction per {by}\n\n" + markdown_table(shown)
    return text
