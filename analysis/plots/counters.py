"""Counters per particle-step against N (issue 44 item 3): instructions, last-level cache misses
and branch misses of each configuration, over its particle-steps (N S K; a time unit for an
engine without sub-steps), where the run counted them: from the hardware, or simulated under
cachegrind (`counters: "simulate"`, runs.csv's `counters_source` says which). The caches of
meta.json's ceilings mark where a particle-step's STATE_BYTES of N particles outgrow each level,
which is where misses per step should rise.
"""
from __future__ import annotations

import pandas as pd

from analysis.common.stats import RUN_KEYS
from analysis.plots.ceilings import STATE_BYTES

COUNTERS = [("instructions", "instructions"), ("cache_misses", "last-level cache misses"),
            ("branch_misses", "branch misses")]


def counters_per_step(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per configuration with a counted run: RUN_KEYS, `source` (the counters_source of
    its runs, or `hardware` for a sweep older than the column) and each counter's median over
    its ok runs per particle-step."""
    present = [c for c, _ in COUNTERS if c in runs.columns]
    if not present:
        return pd.DataFrame()
    counted = runs[(runs["status"] == "ok") & runs[present].notna().any(axis=1)].copy()
    if counted.empty:
        return pd.DataFrame()
    sub_steps = counted["slow_factor"].fillna(1) if "slow_factor" in counted else 1
    steps = counted["N"] * counted["S"] * sub_steps
    for c in present:
        counted[c] = counted[c] / steps
    source = (counted["counters_source"].fillna("") if "counters_source" in counted
              else pd.Series("hardware", index=counted.index))
    counted["source"] = source.replace("", "hardware")
    keys = [k for k in RUN_KEYS if k in counted.columns]
    grouped = counted.groupby(keys, dropna=False)
    out = grouped[present].median()
    out["source"] = grouped["source"].agg(lambda s: ", ".join(sorted(set(s))))
    return out.reset_index()


def cache_marks(meta: dict) -> list[tuple[str, float]]:
    """(name, N) for each data or unified cache of meta.json's ceilings: the N whose particles'
    STATE_BYTES fill it."""
    caches = (meta.get("ceilings") or {}).get("caches") or []
    marks = []
    for cache in caches:
        if cache.get("type") in ("Data", "Unified") and cache.get("size_bytes"):
            suffix = "d" if cache["type"] == "Data" else ""
            marks.append((f"L{cache['level']}{suffix}", cache["size_bytes"] / STATE_BYTES))
    return marks
