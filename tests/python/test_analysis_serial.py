"""Karp-Flatt, Amdahl fit and cost per unit of work on fixtures/analysis_serial, an 8-core sweep
whose times were made from Amdahl's law by hand:

  N=1000: t(T) = 10 (0.1 + 0.9 / T) = 10, 5.5, 3.25, 2.125 s at T = 1, 2, 4, 8, so e = 0.1 at
          every T and f = 0.1; T=16 (5 s, oversubscribed) is past the cores and not fitted.
  N=2000: 10, 5.5, 4.0, 3.875 s: 1/S = 0.55, 0.4, 0.3875, so e = 0.1, 0.2, 0.3 (rising: overhead
          grows with T), and f = sum(x^2 e) / sum(x^2) with x = 1 - 1/T = (1/2, 3/4, 7/8):
          (47/128) / (101/64) = 47/202.
"""
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from analysis.common.load import load_results
from analysis.plots.serial import amdahl_speedup, fit_amdahl, karp_flatt
from analysis.plots.speedup import speedup_table

FIXTURES = Path(__file__).parent / "fixtures"


@pytest.fixture(scope="module")
def table():
    results = load_results(FIXTURES / "analysis_serial")
    assert results.cores == 8
    return speedup_table(results.runs, results.cores, results.declaration)


def rows(table, n):
    return table[table["N"] == n].set_index("T")


def test_karp_flatt_is_flat_for_a_fixed_serial_part(table):
    e = rows(table, 1000)["karp_flatt"]
    assert np.isnan(e[1])
    assert e[[2, 4, 8]].tolist() == pytest.approx([0.1, 0.1, 0.1])


def test_karp_flatt_rises_with_growing_overhead(table):
    assert rows(table, 2000)["karp_flatt"][[2, 4, 8]].tolist() == pytest.approx([0.1, 0.2, 0.3])


def test_amdahl_fit_ignores_oversubscribed_threads(table):
    n1000 = rows(table, 1000)
    assert n1000["amdahl_f"].tolist() == pytest.approx([0.1] * 5)
    # The prediction at T=16 is Amdahl's, not the measured 2x.
    assert n1000["amdahl_speedup"][16] == pytest.approx(1 / (0.1 + 0.9 / 16))
    assert n1000["speedup"][16] == pytest.approx(2.0)


def test_amdahl_fit_is_least_squares_of_normalised_time(table):
    assert rows(table, 2000)["amdahl_f"].iloc[0] == pytest.approx(47 / 202, rel=1e-12)


def test_amdahl_fit_without_cores_uses_every_T():
    t = np.array([1, 2, 16])
    s = np.array([1.0, 1 / 0.55, 2.0])
    # x = (1/2, 15/16), e = (0.1, (0.5 - 1/16) / (15/16) = 7/15)
    expected = (0.25 * 0.1 + (15 / 16) ** 2 * 7 / 15) / (0.25 + (15 / 16) ** 2)
    assert fit_amdahl(t, s) == pytest.approx(expected)
    assert karp_flatt(s, t)[2] == pytest.approx(7 / 15)


def test_amdahl_fit_is_clamped_and_empty_without_parallel_runs():
    assert fit_amdahl([1, 2], [1.0, 2.5]) == 0.0          # superlinear: e < 0
    assert np.isnan(fit_amdahl([1], [1.0]))
    assert amdahl_speedup(0.0, 8) == pytest.approx(8.0)


def test_cost_per_unit_of_work(table):
    n1000 = rows(table, 1000)
    # 10 s over 1000 particles x 10 steps = 1 ms; over 4 995 000 pair tests = 2002 ns.
    assert n1000["ns_per_particle_step"][1] == pytest.approx(1e6)
    assert n1000["ns_per_pair_test"][1] == pytest.approx(1e10 / 4995000)
    # K = 2 doubles the sub-steps.
    assert rows(table, 2000)["ns_per_particle_step"][1] == pytest.approx(1e10 / (2000 * 10 * 2))


def serial_rows(runs, cores=8):
    """The report's serial-fraction rows of `runs`, by their first cell (N)."""
    from analysis.plots.sections import serial_section
    text = serial_section(speedup_table(runs, cores), cores)
    lines = [line for line in text.splitlines() if re.match(r"\| \d", line)]
    return text, {line.split(" | ")[0].strip("| "): line for line in lines}


def test_each_row_says_what_makes_its_serial_fraction_doubtful():
    runs = load_results(FIXTURES / "analysis_serial").runs
    n1000 = runs[(runs["N"] == 1000) & (runs["status"] == "ok")]
    runs = pd.concat([runs] + [n1000.assign(wall_s=n1000["wall_s"] * 1.01)] * 2)
    runs.loc[(runs["N"] == 2000) & (runs["T"] == 2), "wall_s"] = 12.0  # slower than T=1
    text, rows = serial_rows(runs)
    assert "| caveat |" in text
    # Three repetitions or more, fitted within the cores: only T=16 is doubtful.
    assert rows["1000"].endswith(
        "| T=16 beyond the 8 cores: e there is oversubscription (left out of f) |")
    # T=2 slower than T=1 (speed-up 0.83, e = 1.4), from one repetition each.
    assert "| 1.4 |" in rows["2000"]
    assert ("| speed-up below 1 at T=2: no serial fraction explains that, f and e there measure "
            "overhead; 1 repetition(s) at T=1, 2, 4, 8: minima as noisy as one run; raise "
            "`repetitions` to 3 or more |") in rows["2000"]
    # Nothing doubtful, no caveat column.
    text, _ = serial_rows(runs[(runs["N"] == 1000) & (runs["T"] <= 8)])
    assert "| caveat |" not in text and text.endswith("| 0.1 | 0.1 | 0.1 | 0.1 |\n")
