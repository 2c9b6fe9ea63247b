"""Speed-up, efficiency and speed-up over brute on the hand-written fixture
fixtures/analysis_threads/runs.csv, whose expected values were worked out by hand:

  brute N=100: T=1 min 2.0, T=2 min 1.0, T=4 min 1.25 (the 0.5 run failed and must not count)
  brute N=200: T=1 8.0, T=2 4.0, T=4 2.5
  grid N=100 G=2: T=1 1.0, T=2 0.6, T=4 0.5;  G=4: T=1 0.8, T=2 0.5, T=4 0.4 (+ a timeout)
"""
from pathlib import Path

import pandas as pd
import pytest

from analysis.common.csv_out import write_csv
from analysis.common.load import load_results, normalise
from analysis.plots.speedup import speedup_table

FIXTURES = Path(__file__).parent / "fixtures"


@pytest.fixture(scope="module")
def table():
    results = load_results(FIXTURES / "analysis_threads")
    return speedup_table(results.runs, declaration=results.declaration)


def row(table, engine, n, t, g=None):
    match = (table["engine"] == engine) & (table["N"] == n) & (table["T"] == t)
    match &= table["G"].isna() if g is None else (table["G"] == g)
    assert match.sum() == 1, f"expected one row for {engine} N={n} T={t} G={g}"
    return table[match].iloc[0]


def test_one_row_per_configuration(table):
    assert len(table) == 12


@pytest.mark.parametrize("engine,n,t,g,wall,speedup,efficiency", [
    ("brute", 100, 1, None, 2.0, 1.0, 1.0),
    ("brute", 100, 2, None, 1.0, 2.0, 1.0),
    ("brute", 100, 4, None, 1.25, 1.6, 0.4),   # the failed 0.5 s run is ignored
    ("brute", 200, 2, None, 4.0, 2.0, 1.0),
    ("brute", 200, 4, None, 2.5, 3.2, 0.8),
    ("grid", 100, 2, 2, 0.6, 1.0 / 0.6, 1.0 / 1.2),
    ("grid", 100, 4, 4, 0.4, 2.0, 0.5),        # the 600 s timeout is ignored
])
def test_speedup_and_efficiency(table, engine, n, t, g, wall, speedup, efficiency):
    r = row(table, engine, n, t, g)
    assert r["wall_s_min"] == pytest.approx(wall)
    assert r["speedup"] == pytest.approx(speedup)
    assert r["efficiency"] == pytest.approx(efficiency)


def test_baseline_is_per_G_not_shared_across_grid_sizes(table):
    # G=4 has its own T=1 (0.8 s): using G=2's 1.0 s would give 2.5 at T=4.
    assert row(table, "grid", 100, 4, 4)["speedup"] == pytest.approx(0.8 / 0.4)


def test_speedup_vs_brute_uses_brute_at_one_thread_on_same_scene(table):
    assert row(table, "grid", 100, 1, 2)["speedup_vs_brute"] == pytest.approx(2.0)
    assert row(table, "grid", 100, 4, 4)["speedup_vs_brute"] == pytest.approx(5.0)
    assert row(table, "brute", 200, 4)["speedup_vs_brute"] == pytest.approx(3.2)


def test_failures_are_counted_per_configuration(table):
    assert row(table, "brute", 100, 4)["failed"] == 1
    assert row(table, "brute", 100, 4)["reps"] == 1
    assert row(table, "grid", 100, 4, 4)["failed"] == 1
    assert table["failed"].sum() == 2


def test_configuration_without_baseline_gets_empty_speedup():
    runs = normalise(pd.DataFrame([
        dict(engine="brute", N=10, T=1, status="ok", wall_s=1.0),
        dict(engine="brute", N=20, T=2, status="ok", wall_s=1.0),   # no T=1 for N=20
        dict(engine="brute", N=20, T=1, status="crashed", wall_s=""),
    ]))
    table = speedup_table(runs)
    n20 = table[(table["N"] == 20) & (table["T"] == 2)].iloc[0]
    assert pd.isna(n20["speedup"]) and pd.isna(n20["efficiency"])
    assert table[table["N"] == 10].iloc[0]["speedup"] == 1.0


def test_speedup_csv_prints_integers_and_empty_cells(table, tmp_path):
    path = tmp_path / "speedup.csv"
    write_csv(table, path)
    text = path.read_text().splitlines()
    header = text[0].split(",")
    for column in ["engine", "N", "L", "r", "S", "slow_factor", "G", "T", "wall_s_min",
                   "speedup", "efficiency", "speedup_vs_brute"]:
        assert column in header
    first = dict(zip(header, text[1].split(",")))
    assert first["N"] == "100" and first["T"] == "1" and first["G"] == ""


def test_speedup_csv_round_trips_at_full_precision(table, tmp_path):
    # grid N=100 G=2 T=2 has speed-up 1.0 / 0.6 = 1.666...: 6 significant digits lose 3e-6.
    path = tmp_path / "speedup.csv"
    write_csv(table, path)
    back = pd.read_csv(path)
    runs = load_results(FIXTURES / "analysis_threads").ok
    grid = runs[(runs["engine"] == "grid") & (runs["G"] == 2)]
    recomputed = grid[grid["T"] == 1]["wall_s"].min() / grid[grid["T"] == 2]["wall_s"].min()
    written = back[(back["engine"] == "grid") & (back["G"] == 2) & (back["T"] == 2)]
    assert abs(written["speedup"].iloc[0] - recomputed) <= 1e-12 * recomputed
    assert back["efficiency"].tolist() == pytest.approx(table["efficiency"].tolist(), rel=1e-15,
                                                        nan_ok=True)
