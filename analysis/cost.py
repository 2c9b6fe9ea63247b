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

Both use the fastest repetition's time and the configuration's pair_tests (a deterministic count:
every repetition has the same value, the median guards against a garbled cell).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from analysis.stats import RUN_KEYS, aggregate

COST_COLUMNS = ["ns_per_pair_test", "ns_per_particle_step"]


def particle_steps(table: pd.DataFrame) -> pd.Series:
    return table["N"] * table["S"] * table["slow_factor"].fillna(1.0)


def add_cost(table: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    pairs = aggregate(runs, "pair_tests")[RUN_KEYS + ["pair_tests_median"]]
    out = table.merge(pairs, on=RUN_KEYS, how="left")
    tests = out["pair_tests_median"].where(out["pair_tests_median"] > 0)
    out["ns_per_pair_test"] = 1e9 * out["wall_s_min"] / tests
    out["ns_per_particle_step"] = 1e9 * out["wall_s_min"] / particle_steps(out).where(
        lambda steps: steps > 0, np.nan)
    return out.drop(columns="pair_tests_median")
