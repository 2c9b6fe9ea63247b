"""Ranks: runs of an engine that uses P (psim's declaration: the mpi engine), one simulation on P
processes of T threads each. Strong scaling against P and P x T, the communication share of
the loop, and weak scaling over P: the contents of ranks.csv.

  workers          P x T, the cores the run's threads take
  speedup_P        wall_s_min at P = 1, T = 1 of the same configuration / wall_s_min here
  efficiency_P     speedup_P / workers
  comm_share       the slowest rank's seconds in MPI calls over the loop, comm_s_max / wall_s
                   (median over ok repetitions); wait_share the same of wait_s_max, the part of
                   it spent waiting for the last rank to arrive (load imbalance)
  halo_per_rank    halo_particles_mean / the run's sub-steps: copies a rank holds per sub-step

A weak series over P is a P = 1 configuration of N0 particles and those equal to it in everything
but N (and L) and P, at the same T, with N = P x N0: the same particles per rank (configs/mpi.json
zips such runs with the strong ones). weak_efficiency_P = t(P = 1) / t(P), 1 when P ranks do P
times the work in the same time.
"""
from __future__ import annotations

import pandas as pd

from analysis.common.declaration import Declaration
from analysis.common.load import CONFIG_PARAMS

# A configuration apart from its ranks and threads.
RANK_KEYS = [c for c in CONFIG_PARAMS if c != "P"]
# What may grow along a weak series over P, as along one over T (weak.py).
WEAK_KEYS = [c for c in RANK_KEYS if c not in ("N", "L")] + ["T"]

RANK_COLUMNS = RANK_KEYS + ["P", "T", "workers", "wall_s_min", "speedup_P", "efficiency_P",
                            "comm_share", "wait_share", "halo_per_rank", "bytes_sent_mean"]
WEAK_RANK_COLUMNS = WEAK_KEYS + ["P", "N", "L", "wall_s_min", "weak_efficiency_P"]


def ranked_engines(declaration: Declaration, table: pd.DataFrame) -> list[str]:
    """The engines of the sweep that run on P ranks: those the declaration says use P, and
    (without a declaration) those whose rows have a P."""
    with_p = table.dropna(subset=["P"])
    return sorted(e for e in with_p["engine"].unique() if declaration.uses(e, "P"))


def shares(runs: pd.DataFrame) -> pd.DataFrame:
    """Per configuration (RANK_KEYS, P, T), the medians over ok repetitions of the
    communication and waiting shares of the loop, and the halo and bytes per rank."""
    ok = runs[(runs["status"] == "ok") & runs["P"].notna()].copy()
    if ok.empty or "comm_s_max" not in ok.columns:
        return pd.DataFrame(columns=RANK_KEYS + ["P", "T", "comm_share", "wait_share",
                                                 "halo_per_rank", "bytes_sent_mean"])
    ok["comm_share"] = ok["comm_s_max"] / ok["wall_s"]
    ok["wait_share"] = ok["wait_s_max"] / ok["wall_s"]
    sub_steps = ok["S"] * ok["slow_factor"].fillna(1)
    ok["halo_per_rank"] = ok["halo_particles_mean"] / sub_steps.where(sub_steps > 0)
    return (ok.groupby(RANK_KEYS + ["P", "T"], dropna=False)
            [["comm_share", "wait_share", "halo_per_rank", "bytes_sent_mean"]]
            .median().reset_index())


def ranks_table(table: pd.DataFrame, runs: pd.DataFrame,
                declaration: Declaration | None = None) -> pd.DataFrame:
    """One row per configuration of an engine that runs on ranks, from the speed-up table
    (speedup.py) and the runs; empty when the sweep has none."""
    engines = ranked_engines(declaration or Declaration(), table)
    rows = table[table["engine"].isin(engines)].dropna(subset=["P", "wall_s_min"]).copy()
    if rows.empty:
        return pd.DataFrame(columns=RANK_COLUMNS)
    rows["workers"] = rows["P"] * rows["T"]
    baseline = (rows[(rows["P"] == 1) & (rows["T"] == 1)][RANK_KEYS + ["wall_s_min"]]
                .rename(columns={"wall_s_min": "baseline_s"}))
    rows = rows.merge(baseline, on=RANK_KEYS, how="left")
    rows["speedup_P"] = rows["baseline_s"] / rows["wall_s_min"]
    rows["efficiency_P"] = rows["speedup_P"] / rows["workers"]
    rows = rows.merge(shares(runs), on=RANK_KEYS + ["P", "T"], how="left")
    rows = rows.sort_values(["engine", "N", "P", "T"], kind="stable")
    return rows[RANK_COLUMNS].reset_index(drop=True)


def weak_ranks_table(ranks: pd.DataFrame) -> pd.DataFrame:
    """One row per configuration of every weak series over P in the ranks table."""
    parts = []
    for _, group in ranks.groupby(WEAK_KEYS, dropna=False, sort=True):
        for n0 in sorted(group.loc[group["P"] == 1, "N"].unique()):
            series = group[group["N"] == n0 * group["P"]].sort_values("P").copy()
            if series["P"].nunique() < 2:
                continue
            p1 = series.loc[series["P"] == 1, "wall_s_min"].iloc[0]
            series["weak_efficiency_P"] = p1 / series["wall_s_min"]
            parts.append(series)
    if not parts:
        return pd.DataFrame(columns=WEAK_RANK_COLUMNS)
    return pd.concat(parts)[WEAK_RANK_COLUMNS].reset_index(drop=True)
