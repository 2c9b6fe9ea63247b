"""Summary tables for the report: optimal thread count and peak speed-up (the 2019 report's
tables in sections 7.2 and 9.2), failed runs, and state-hash agreement. Pure functions over the
speedup table and the runs frame.
"""
from __future__ import annotations

import pandas as pd

from analysis.common.load import CONFIG_PARAMS, SCENE_PARAMS


def peak_table(speedup: pd.DataFrame) -> pd.DataFrame:
    """Per configuration (every parameter but T): the T with the highest speed-up, that
    speed-up, its efficiency, and the minimum wall times at T=1 and at that T. Configurations
    without a speed-up (no T=1 baseline) or with one thread count only are left out. Ties go to
    the smaller T: the same speed for fewer cores is the better choice."""
    rated = speedup.dropna(subset=["speedup"])
    if rated.empty:
        return pd.DataFrame(columns=CONFIG_PARAMS + ["optimal_T", "peak_speedup",
                                                     "efficiency", "wall_s_T1", "wall_s_best",
                                                     "threads_tried"])
    rows = []
    for key, group in rated.groupby(CONFIG_PARAMS, dropna=False, sort=True):
        if len(group) < 2:
            continue  # one thread count (a weak-scaling point): no optimum to choose
        group = group.sort_values("T")
        best = group.loc[group["speedup"].idxmax()]
        t1 = group[group["T"] == 1]["wall_s_min"]
        rows.append(dict(zip(CONFIG_PARAMS, key),
                         optimal_T=int(best["T"]), peak_speedup=best["speedup"],
                         efficiency=best["efficiency"],
                         wall_s_T1=t1.iloc[0] if len(t1) else float("nan"),
                         wall_s_best=best["wall_s_min"],
                         threads_tried=len(group)))
    return pd.DataFrame(rows)


def failure_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Every non-ok run with what identifies it and why it failed."""
    failed = runs[runs["status"] != "ok"]
    columns = [c for c in CONFIG_PARAMS + ["T", "rep", "status", "exit_code", "error"]
               if c in failed.columns]
    return failed[columns].reset_index(drop=True)


def hash_agreement(runs: pd.DataFrame, exact_engines: set[str] | None = None) -> pd.DataFrame:
    """Per scene: how many distinct final-state hashes the exact engines produced across
    every engine, G, T and repetition. docs/model.md, "Determinism", promises exactly one.
    Engines psim declares inexact (a different dynamics, or collisions dropped on purpose) are
    left out; without a declaration (exact_engines None) every engine is held to it."""
    exact = runs["engine"].isin(exact_engines) if exact_engines is not None else True
    ok = runs[(runs["status"] == "ok") & exact]
    if "state_hash" not in ok.columns or ok["state_hash"].isna().all():
        return pd.DataFrame(columns=SCENE_PARAMS + ["runs", "distinct_hashes"])
    ok = ok.dropna(subset=["state_hash"])
    grouped = ok.groupby(SCENE_PARAMS, dropna=False, sort=True)["state_hash"]
    table = grouped.agg(runs="count", distinct_hashes="nunique").reset_index()
    return table


def cpu_share(runs: pd.DataFrame, cores: int | None) -> pd.DataFrame:
    """Per engine, P and T, the median share of the CPUs the run could use that it actually got:
    (user + sys) / (process wall time * min(P T, cores)), P the ranks of a run of the mpi engine
    (its rusage holds every rank's), 1 for the rest. Near 1 means the run had its cores to
    itself. Well below 1 at P T = 1 means the machine was busy, and then speed-ups are inflated:
    with more threads a process wins a larger share of a contended CPU, which looks like
    parallel speed-up but is not. Runs whose threads mostly wait (small N) also score low, so
    P T = 1 is the reference row. A sweep without ranks has no P column."""
    needed = ["user_s", "sys_s", "process_s"]
    ok = runs[(runs["status"] == "ok")].dropna(subset=needed)
    ok = ok[ok["process_s"] > 0]
    ranked = "P" in ok.columns and ok["P"].notna().any()
    keys = ["engine", "P", "T"] if ranked else ["engine", "T"]
    if ok.empty:
        return pd.DataFrame(columns=keys + ["runs", "cpu_share"])
    threads = ok["T"] * (ok["P"].fillna(1) if ranked else 1)
    usable = threads.clip(upper=cores) if cores else threads
    share = (ok["user_s"] + ok["sys_s"]) / (ok["process_s"] * usable)
    return (ok.assign(cpu_share=share).groupby(keys, sort=True, dropna=False)["cpu_share"]
            .agg(runs="count", cpu_share="median").reset_index())
