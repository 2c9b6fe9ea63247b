"""Counters per particle-step against N (analysis/plots/counters.py, issue 44 item 3) on hand-made
runs: each counter over N S K, the median of the ok runs, the source said, runs without counts
left out; the caches' N marks from meta.json's ceilings; the plot drawn only with two N counted."""
import math

import pandas as pd

from analysis.plots.ceilings import STATE_BYTES
from analysis.plots.counters import cache_marks, counters_per_step
from analysis.plots.figures_hpc import plot_counters_per_step


def run(n, instructions, source="simulated", status="ok", k=1):
    return dict(engine="cells", N=n, L=1000, r=1, S=10, slow_factor=k, T=1, G=math.nan,
                seed="1", speed_min=math.nan, speed_max=math.nan, scene_file="", pin="close",
                neighbour="none", wall_stop="per-coordinate", P=math.nan, status=status,
                instructions=instructions, cache_misses=instructions / 100,
                branch_misses=math.nan, counters_source=source)


RUNS = pd.DataFrame([run(100, 1e6), run(100, 3e6), run(100, 9e9, status="failed"),
                     run(1000, 2e7, k=2), run(5000, math.nan, source="")])


def test_each_counter_per_particle_step_the_median_of_the_ok_runs():
    counts = counters_per_step(RUNS).set_index("N")
    assert list(counts.index) == [100, 1000]  # N = 5000 counted nothing
    assert counts.loc[100, "instructions"] == 2e6 / (100 * 10)  # the failed run left out
    assert counts.loc[1000, "instructions"] == 2e7 / (1000 * 10 * 2)  # K sub-steps a unit
    assert counts.loc[100, "cache_misses"] == counts.loc[100, "instructions"] / 100
    assert set(counts["source"]) == {"simulated"}


def test_a_sweep_without_counters_gives_nothing_to_draw(tmp_path):
    empty = counters_per_step(RUNS.drop(columns=["instructions", "cache_misses", "branch_misses"]))
    assert empty.empty
    assert plot_counters_per_step(empty, [], tmp_path / "c") is None
    one_n = counters_per_step(RUNS[RUNS["N"] == 100])
    assert plot_counters_per_step(one_n, [], tmp_path / "c") is None


def test_the_caches_mark_where_the_state_outgrows_them(tmp_path):
    meta = {"ceilings": {"caches": [
        {"level": 1, "type": "Data", "size_bytes": 48 * 1024},
        {"level": 1, "type": "Instruction", "size_bytes": 64 * 1024},
        {"level": 2, "type": "Unified", "size_bytes": 2 << 20}]}}
    assert cache_marks(meta) == [("L1d", 48 * 1024 / STATE_BYTES), ("L2", (2 << 20) / STATE_BYTES)]
    assert cache_marks({}) == []
    path = plot_counters_per_step(counters_per_step(RUNS), cache_marks(meta), tmp_path / "c")
    assert path is not None and path.is_file()
