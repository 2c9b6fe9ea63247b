"""Speed-up and efficiency per configuration: the contents of speedup.csv.

  speedup          = wall_s_min at T=1 / wall_s_min at T, same engine and every other parameter
  efficiency       = speedup / T
  speedup_vs_brute = wall_s_min of the reference engine (psim declares brute) at T=1 on the
                     same scene / wall_s_min here (the 2019 report's "speed-up over the
                     sequential implementation"); empty when no reference is declared. An
                     external program's wall_s is its whole process, so its speed-up is
                     against the reference's minimum process_s instead
  karp_flatt, amdahl_f, amdahl_speedup          serial fraction (serial.py)
  ns_per_pair_test, ns_per_particle_step        cost per unit of work (cost.py)
  pair_peak_pct, bandwidth_pct, loop_share_pct, scaling_vs_machine
                                                against this machine's ceilings (ceilings.py)

Minima, not means: on a shared machine noise only ever adds time, so the minimum is the best
estimate of what the code costs. A configuration without a T=1 run (or whose T=1 runs all
failed) gets an empty speedup; the whole sweep lacking T=1 is rejected earlier by
load.require_usable.
"""
from __future__ import annotations

import pandas as pd

from analysis.plots.ceilings import CEILING_COLUMNS, Ceilings, add_ceilings
from analysis.plots.cost import COST_COLUMNS, add_cost
from analysis.common.declaration import Declaration
from analysis.common.load import CONFIG_PARAMS, SCENE_PARAMS
from analysis.plots.serial import SERIAL_COLUMNS, add_serial_fraction
from analysis.common.stats import RUN_KEYS, aggregate, failures, group_runs

OUTPUT_COLUMNS = ["engine", "N", "L", "r", "S", "slow_factor", "G", "P", "T", "seed", "speed_min",
                  "speed_max", "scene_file", "pin", "neighbour", "wall_stop", "overlap", "engine_ran",
                  "reps",
                  "failed",
                  "wall_s_min", "wall_s_median", "wall_s_max", "speedup", "efficiency",
                  "speedup_vs_brute"] + SERIAL_COLUMNS + COST_COLUMNS + CEILING_COLUMNS


def wall_table(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per configuration (including those whose runs all failed, with empty times)."""
    walls = aggregate(runs, "wall_s")
    table = failures(runs).merge(walls, on=RUN_KEYS, how="left")
    table["reps"] = table["reps"].fillna(0).astype(int)
    table["engine_ran"] = engine_ran(runs, table)
    return table


def engine_ran(runs: pd.DataFrame, table: pd.DataFrame) -> pd.Series:
    """What `auto` actually picked (the most frequent choice among ok runs); the configured
    engine for the others or when the harness did not record it."""
    ok = runs[(runs["status"] == "ok")]
    if "engine_ran" not in ok.columns or ok["engine_ran"].isna().all():
        return table["engine"]
    picked = group_runs(ok.dropna(subset=["engine_ran"]))["engine_ran"].agg(
        lambda s: s.value_counts().index[0]).reset_index()
    merged = table[RUN_KEYS].merge(picked, on=RUN_KEYS, how="left")
    return merged["engine_ran"].fillna(table["engine"]).values


def add_speedup(table: pd.DataFrame) -> pd.DataFrame:
    baseline = (table[table["T"] == 1][CONFIG_PARAMS + ["wall_s_min"]]
                .rename(columns={"wall_s_min": "baseline_s"}))
    # pandas merges NaN keys with NaN keys, which is what empty G / scene_file need here.
    out = table.merge(baseline, on=CONFIG_PARAMS, how="left")
    out["speedup"] = out["baseline_s"] / out["wall_s_min"]
    out["efficiency"] = out["speedup"] / out["T"]
    return out.drop(columns="baseline_s")


def add_speedup_vs_brute(table: pd.DataFrame, reference: str | None,
                         runs: pd.DataFrame | None = None,
                         programs: frozenset[str] | set[str] = frozenset()) -> pd.DataFrame:
    brute = table[(table["engine"] == reference) & (table["T"] == 1)]
    # Several pins can give several sequential baselines for one scene: the fastest is the
    # honest reference.
    baseline = (brute.groupby(SCENE_PARAMS, dropna=False)["wall_s_min"].min().reset_index()
                .rename(columns={"wall_s_min": "brute_s"}))
    out = table.merge(baseline, on=SCENE_PARAMS, how="left")
    out["speedup_vs_brute"] = out["brute_s"] / out["wall_s_min"]
    if programs and runs is not None:
        # An external program's wall_s is its whole process (it has no timer of its own): set
        # against the reference's whole process, not against its simulation loop.
        ok = runs[(runs["engine"] == reference) & (runs["T"] == 1) & (runs["status"] == "ok")]
        process = (ok.groupby(SCENE_PARAMS, dropna=False)["process_s"].min().reset_index()
                   .rename(columns={"process_s": "brute_process_s"}))
        out = out.merge(process, on=SCENE_PARAMS, how="left")
        program = out["engine"].isin(programs)
        out.loc[program, "speedup_vs_brute"] = (out.loc[program, "brute_process_s"]
                                                / out.loc[program, "wall_s_min"])
        out = out.drop(columns="brute_process_s")
    return out.drop(columns="brute_s")


def speedup_table(runs: pd.DataFrame, cores: int | None = None,
                  declaration: Declaration | None = None,
                  programs: frozenset[str] | set[str] = frozenset(),
                  ceilings: Ceilings | None = None) -> pd.DataFrame:
    """`cores` bounds the Amdahl fit (serial.py); None fits over every T. The declaration
    (meta.json) names the reference engine of speedup_vs_brute; None leaves it empty.
    `programs` (meta.json's external programs) are timed as whole processes. `ceilings`
    (meta.json's) fill CEILING_COLUMNS; None leaves them empty."""
    reference = (declaration or Declaration()).reference
    table = add_speedup_vs_brute(add_speedup(wall_table(runs)), reference, runs, programs)
    table = add_ceilings(add_cost(add_serial_fraction(table, cores), runs), runs, ceilings)
    table = table.sort_values(["engine", "N", "L", "r", "S", "slow_factor", "G", "P", "T"],
                              na_position="first", kind="stable")
    return table[OUTPUT_COLUMNS].reset_index(drop=True)

