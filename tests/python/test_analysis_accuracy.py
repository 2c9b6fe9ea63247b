"""The accuracy computations (analysis/accuracy/cli.py) on a fixture with known errors, and
`make accuracy QUICK=1`'s pieces end to end on a real quick sweep (in make test)."""
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from analysis.accuracy import cli as accuracy
from analysis.common.declaration import Declaration
from analysis.common.load import load_results

ROOT = Path(__file__).resolve().parents[2]


FIXTURE = ROOT / "tests" / "python" / "fixtures" / "accuracy"
EXACT = "event"  # the fixture's exact engine (a sweep's meta.json declares it)


@pytest.fixture
def table():
    seeds = accuracy.with_reference(accuracy.per_seed(load_results(FIXTURE).runs), EXACT)
    return accuracy.accuracy_table(seeds)


def row(table, engine, k):
    match = table[(table["engine"] == engine) &
                  ((table["slow_factor"] == k) if k else table["slow_factor"].isna())]
    assert len(match) == 1
    return match.iloc[0]


def test_kinetic_theory_values_computed_by_hand():
    # N=1000, L=20000, r=1, <v^2> = 1e6: 2 (2.5e-6) 2 sqrt(pi 5e5) g, g = 1.0000123
    assert accuracy.enskog_rate(1000, 20000, 1, 1e6) == pytest.approx(0.0125332952, rel=1e-8)
    assert accuracy.enskog_rate(100, 100, 1, 4) == pytest.approx(0.1054058538, rel=1e-8)
    assert accuracy.henderson_z(0.2) == pytest.approx(1.5703125)


def test_rate_errors_against_event_with_standard_error(table):
    k1 = row(table, "auto", 1)
    # seed 1: 40/50 - 1 = -0.2, seed 2: 54/60 - 1 = -0.1
    assert k1["rate_err_event"] == pytest.approx(-0.15)
    assert k1["rate_err_event_se"] == pytest.approx(0.05)
    assert row(table, "auto", 4)["rate_err_event"] == pytest.approx(0)
    assert row(table, "event", None)["rate_err_event"] == 0
    # rate = 2 pairs / (N S): (0.08 + 0.108) / 2
    assert k1["rate"] == pytest.approx(0.094)


def test_pressure_energy_dropped_and_time(table):
    k1 = row(table, "auto", 1)
    # P = 360 / (4 1000 10), <v^2> = 2 5000 / 100 = 100, Z = P 1e6 / (100 100 / 2) = 1.8 vs 2
    assert k1["z_err_event"] == pytest.approx(-0.1)
    exact = row(table, "event", None)
    assert exact["z_err_henderson"] == pytest.approx(2 / accuracy.henderson_z(math.pi * 1e-4) - 1)
    assert k1["energy_drift_max"] == pytest.approx(1e-4)
    assert k1["dropped_per_collision"] == pytest.approx(0.2)
    # event: minimum over repetitions per seed (0.4, 0.6), then the mean over seeds
    assert exact["wall_s_min"] == pytest.approx(0.5)
    # brute's timed-out seed is left out: one seed, no standard error
    brute = row(table, "brute", 4)
    assert brute["seeds"] == 1 and math.isnan(brute["rate_err_event_se"])


def test_cheapest_setting_within_one_percent(table):
    cheapest = accuracy.cheapest_within(table, EXACT)
    assert len(cheapest) == 1
    best = cheapest.iloc[0]
    # auto K=4 (0.3 s) beats auto K=16 (0.9 s) and brute K=4 (0.8 s); K=1 is 15% off
    assert best["engine"] == "auto" and best["slow_factor"] == 4
    assert best["wall_s_min"] == pytest.approx(0.3)
    assert best["event_wall_s"] == pytest.approx(0.5)
    assert "none within" in accuracy.report_markdown(
        table, accuracy.cheapest_within(table, EXACT, tolerance=-1), pd.DataFrame(),
        pd.DataFrame(), EXACT)


def test_every_section_lists_the_scenes_in_one_order(monkeypatch):
    runs = load_results(FIXTURE).runs
    # Three scenes whose labels' text would sort r=160 before r=80.
    runs = pd.concat([runs.assign(r=r) for r in (160.0, 1.0, 80.0)], ignore_index=True)
    seeds = accuracy.with_reference(accuracy.per_seed(runs), EXACT)
    table = accuracy.accuracy_table(seeds)

    def positions(psim, row, seed, engine, k, steps, mode):
        frames = steps + 1 if mode == "print" else 2
        return SimpleNamespace(steps=np.arange(frames),
                               positions=np.zeros((frames, int(row["N"]), 2)))
    monkeypatch.setattr(accuracy, "psim_positions", positions)
    trajectory, _, horizons = accuracy.measure_trajectories("psim", seeds, EXACT, [1, 4], 4, 3)
    report = accuracy.report_markdown(table, accuracy.cheapest_within(table, EXACT), trajectory,
                                      horizons, EXACT)
    orders = {}
    for section in report.split("\n## ")[1:]:
        rows = [line.split(" | ")[0].lstrip("| ") for line in section.splitlines()
                if line.startswith("| N=")]
        orders[section.splitlines()[0]] = list(dict.fromkeys(rows))
    assert len(orders) == 4
    by_value = [f"r={r} " for r in (1, 80, 160)]
    for title, scenes in orders.items():
        assert [next(r for r in by_value if r in scene) for scene in scenes] == by_value, title


def test_no_event_run_is_an_input_error():
    runs = load_results(FIXTURE).runs
    with pytest.raises(accuracy.InputError, match="no successful event run"):
        accuracy.with_reference(accuracy.per_seed(runs[runs["engine"] != EXACT]), EXACT)


def test_the_exact_engine_comes_from_the_declaration():
    declared = Declaration(engines=[
        {"name": "brute", "exact": True, "reference": True},
        {"name": "exactly", "exact": True, "continuous_time": True}])
    assert accuracy.exact_engine(declared) == "exactly"
    with pytest.raises(accuracy.InputError, match="declares no exact continuous-time engine"):
        accuracy.exact_engine(Declaration())


def test_trajectory_deviation_and_chaos_horizon():
    a = np.zeros((4, 2))
    b = np.array([[3.0, 4.0], [0, 0], [0, 0], [0, 0]])  # one particle 5 away: RMS 5/2
    assert accuracy.rms_deviation(a, b, 10) == pytest.approx(0.25)
    series = pd.DataFrame({"t": [1, 2, 3, 4], "deviation": [1e-6, 1e-4, 0.02, 0.3]})
    assert accuracy.chaos_horizon(series) == 3
    assert math.isnan(accuracy.chaos_horizon(series, threshold=1))
