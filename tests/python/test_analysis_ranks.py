"""Runs on ranks (analysis/plots/ranks.py) on hand-made tables: strong scaling over P and P x T
against P = 1, T = 1 of the same configuration, the communication share of the loop from the
slowest rank's seconds, weak series over P found by N = P x N0, and engines without ranks left
out."""
import math

import pandas as pd

from analysis.common.declaration import Declaration
from analysis.common.load import CONFIG_PARAMS
from analysis.plots.ranks import ranks_table, weak_ranks_table

DECLARATION = Declaration(engines=[{"name": "mpi", "uses": ["T", "P", "slow_factor"]},
                                   {"name": "brute", "uses": ["T", "slow_factor"]}])


def config(engine, n, p, t, wall):
    row = {c: float("nan") for c in CONFIG_PARAMS}
    row.update(engine=engine, N=n, L=1000.0, r=1.0, S=100.0, slow_factor=1.0, P=p, T=t,
               wall_s_min=wall)
    return row


def run(engine, n, p, t, wall, comm, wait, halo):
    row = config(engine, n, p, t, wall)
    row.update(status="ok", wall_s=wall, comm_s_max=comm, wait_s_max=wait,
               halo_particles_mean=halo, bytes_sent_mean=8 * halo)
    return row


def frames(rows):
    table = pd.DataFrame([config(*r[:5]) for r in rows])
    runs = pd.DataFrame([run(*r) for r in rows])
    return table, runs


ROWS = [("brute", 400, float("nan"), 1, 4.0, float("nan"), float("nan"), float("nan")),
        ("mpi", 400, 1, 1, 2.0, 0.0, 0.0, 0.0),
        ("mpi", 400, 2, 1, 1.25, 0.25, 0.125, 300.0),
        ("mpi", 400, 2, 2, 0.8, 0.4, 0.2, 300.0),
        ("mpi", 800, 2, 1, 2.5, 0.5, 0.25, 400.0),
        ("mpi", 1600, 4, 1, 4.0, 2.0, 1.0, 500.0)]


def test_strong_scaling_against_p_and_p_times_t():
    ranks = ranks_table(*frames(ROWS), DECLARATION)
    assert set(ranks["engine"]) == {"mpi"}  # brute runs in one process
    at = ranks.set_index(["N", "P", "T"])
    assert at.loc[(400, 2, 1), "speedup_P"] == 2.0 / 1.25
    assert at.loc[(400, 2, 2), "workers"] == 4
    assert math.isclose(at.loc[(400, 2, 2), "efficiency_P"], 2.0 / 0.8 / 4)
    assert at.loc[(400, 2, 1), "comm_share"] == 0.2
    assert at.loc[(400, 2, 2), "wait_share"] == 0.25
    assert at.loc[(400, 2, 1), "halo_per_rank"] == 3.0  # 300 copies over 100 sub-steps
    assert math.isnan(at.loc[(800, 2, 1), "speedup_P"])  # no P = 1 run of N = 800


def test_weak_series_over_p_keeps_the_particles_per_rank():
    weak = weak_ranks_table(ranks_table(*frames(ROWS), DECLARATION))
    assert list(zip(weak["P"], weak["N"])) == [(1, 400), (2, 800), (4, 1600)]
    assert list(weak["weak_efficiency_P"]) == [1.0, 2.0 / 2.5, 2.0 / 4.0]


def test_a_sweep_without_ranks_has_no_ranks_table():
    table, runs = frames([r for r in ROWS if r[0] == "brute"])
    assert ranks_table(table, runs, DECLARATION).empty
    assert weak_ranks_table(ranks_table(table, runs, DECLARATION)).empty
