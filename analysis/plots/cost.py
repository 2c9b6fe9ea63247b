"""Cost per unit of work, so engines of different complexity compare on one axis.

  ns_per_pair_test      wall_s_min / pair_tests, in ns: what one exact pair test costs
                        together with everything around it (broad phase, order, resolve, ...).
                        Meaningful for comparing brute at different N or T; an engine that
                        prunes pairs pays more per test but makes far fewer.
  ns_per_particle_step  wall_s_min / (N x S x K), in ns: the cost of moving one particle through
                        one sub-step, whatever the algorithm. Flat in N is an O(N) engine; rising
                        linearly in N is O(N^2). The lowest curve at a given N is the engine to
                        use there, which is what `auto` tries to pick. `event` has no sub-steps:
                        its unit is N x S.
  tests_per_needed_pair pair_tests / pair_candidates: the pairs the narrow phase examined for each
                        pair that could collide in its sub-step (the scene's need, the same in
                        every exact discrete engine): how much the broad phase leaves in (1: none;
                        brute's is N^2 / 2 per sub-step over the few that can collide)
  builds_per_substep    broad_phase_builds / (time_reached x K): how often the broad phase built
                        its structure afresh (1: every sub-step, as sweep and bands do; cells
                        keeps its cells and builds in a few; 0: brute and event build none)

They use the fastest repetition's time and the configuration's counts (deterministic: every
repetition has the same value, the median guards against a garbled cell).

auto_versus_fastest answers "where does each engine win, and does `auto` know?": per scene and
thread count, the fastest measured exact engine against the one an engine that picks (auto: its
recorded engine_ran differs from its name) chose.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from analysis.common.labels import picked
from analysis.common.load import SCENE_PARAMS
from analysis.common.stats import RUN_KEYS, aggregate

COST_COLUMNS = ["ns_per_pair_test", "ns_per_particle_step", "tests_per_needed_pair",
                "builds_per_substep"]


def particle_steps(table: pd.DataFrame) -> pd.Series:
    return table["N"] * table["S"] * table["slow_factor"].fillna(1.0)


def add_cost(table: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    counts = ["pair_tests", "pair_candidates", "broad_phase_builds", "time_reached"]
    for column in counts:  # a sweep whose psim did not count them: empty
        runs = runs.assign(**{column: pd.to_numeric(runs[column], errors="coerce")
                              if column in runs.columns else np.nan})
    out = table
    for column in counts:
        out = out.merge(aggregate(runs, column)[RUN_KEYS + [f"{column}_median"]], on=RUN_KEYS,
                        how="left")
    tests = out["pair_tests_median"].where(out["pair_tests_median"] > 0)
    out["ns_per_pair_test"] = 1e9 * out["wall_s_min"] / tests
    out["ns_per_particle_step"] = 1e9 * out["wall_s_min"] / particle_steps(out).where(
        lambda steps: steps > 0, np.nan)
    out["tests_per_needed_pair"] = tests / out["pair_candidates_median"].where(
        out["pair_candidates_median"] > 0)
    substeps = out["time_reached_median"] * out["slow_factor"].fillna(1.0)
    out["builds_per_substep"] = out["broad_phase_builds_median"] / substeps.where(substeps > 0)
    return out.drop(columns=[f"{column}_median" for column in counts])


# A scene at one thread count and pinning: what the engines compete on.
CONTEST_KEYS = SCENE_PARAMS + ["T", "pin"]


def picking_engines(table: pd.DataFrame) -> set[str]:
    """Engines that choose another engine per scene (auto): engine_ran differs from the name."""
    ran = table.dropna(subset=["engine_ran"])
    return set(ran.loc[ran["engine_ran"] != ran["engine"], "engine"])


def auto_versus_fastest(table: pd.DataFrame,
                        exact_engines: set[str] | None = None) -> pd.DataFrame:
    """One row per scene and T where at least two exact engines were measured or a picking
    engine ran: the fastest measured (`fastest`, with its G and time; empty when none was), how
    many engines competed, and for each picking engine its choice (`picked`), its time,
    `picked_measured` (the engine it picked was also swept on its own at this scene and T),
    `picked_is_fastest` (empty unless picked_measured: a pick can only be judged against its
    own engine's time) and `not_judged`, why a pick is not judged ('' where it is or there is
    none). exact_engines None counts every engine that does not pick (use psim's declaration to
    leave out inexact ones)."""
    rated = table.dropna(subset=["wall_s_min"])
    pickers = picking_engines(rated)
    competing = rated[~rated["engine"].isin(pickers)]
    if exact_engines is not None:
        competing = competing[competing["engine"].isin(exact_engines)]
    columns = CONTEST_KEYS + ["engines", "fastest", "fastest_G", "fastest_wall_s", "picker",
                              "picked", "picked_wall_s", "picked_measured", "picked_is_fastest",
                              "not_judged"]
    picks = (rated[rated["engine"].isin(pickers)][CONTEST_KEYS + ["engine", "engine_ran",
                                                                  "wall_s_min"]]
             .rename(columns={"engine": "picker", "engine_ran": "picked",
                              "wall_s_min": "picked_wall_s"}))
    picks["picked"] = picks["picked"].map(picked, na_action="ignore")
    if competing.empty and picks.empty:
        return pd.DataFrame(columns=columns)
    grouped = competing.groupby(CONTEST_KEYS, dropna=False, sort=True)
    best = competing.loc[grouped["wall_s_min"].idxmin().values, CONTEST_KEYS + [
        "engine", "G", "wall_s_min"]].rename(columns={"engine": "fastest", "G": "fastest_G",
                                                      "wall_s_min": "fastest_wall_s"})
    best = best.merge(grouped["engine"].nunique().rename("engines").reset_index(),
                      on=CONTEST_KEYS)
    out = best.merge(picks, on=CONTEST_KEYS, how="outer")
    out = out[(out["engines"] >= 2) | out["picker"].notna()]
    out["engines"] = out["engines"].fillna(0).astype(int)
    swept = (competing[CONTEST_KEYS + ["engine"]].drop_duplicates()
             .rename(columns={"engine": "picked"}).assign(picked_measured=True))
    out = out.merge(swept, on=CONTEST_KEYS + ["picked"], how="left")  # NaN keys match NaN
    out["picked_measured"] = out["picked_measured"].astype("boolean").fillna(False).astype(bool)
    out["picked_is_fastest"] = (out["picked"] == out["fastest"]).where(out["picked_measured"])
    unjudged = out["picker"].notna() & ~out["picked_measured"]
    out["not_judged"] = (out["picked"] + " not swept on its own here").where(unjudged, "")
    out.loc[unjudged & several(out["picked"]), "not_judged"] = (
        "ran " + out["picked"] + " in turn: no one engine to time it against")
    return out[columns].sort_values(CONTEST_KEYS, kind="stable").reset_index(drop=True)


def several(picks: pd.Series) -> pd.Series:
    """Picks of more than one engine: auto switched engines during the run ("cells+sweep")."""
    return picks.fillna("").str.contains("+", regex=False)


def unjudged_picks(contests: pd.DataFrame) -> list[str]:
    """The engines a picking engine chose that were not swept on their own at that scene and T:
    what to add to the sweep's engines (advice.SWEEP_ENGINE) before its choices can be judged."""
    missing = contests[(contests["not_judged"] != "") & ~several(contests["picked"])]
    return sorted(missing["picked"].dropna().unique())
