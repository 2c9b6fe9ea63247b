"""Weak scaling on fixtures/analysis_weak (4 cores), times chosen by hand:

  brute, N ~ sqrt(T): 1000, 1414, 2000 at T = 1, 2, 4 in 1.0, 1.0, 1.25 s -> efficiency 1, 1,
         0.8; scaled speed-up 1, 2, 3.2; Gustafson s = (0·1 + 0.8·3) / (1 + 9) = 0.24.
  cells, N ~ T with L ~ sqrt(T) (constant density): 0.5, 0.625, 0.625 s at T = 1, 2, 4 ->
         efficiency 1, 0.8, 0.8; scaled 1, 1.6, 3.2; s = (0.4·1 + 0.8·3) / 10 = 0.28; T=8 is
         past the cores and left out of the fit.
  sweep at N=1000, T = 1, 2: N constant, strong scaling, not a weak series.
"""
import shutil
from pathlib import Path

import pandas as pd
import pytest

from entry_point import run_tool
from analysis.common import figures
from analysis.common.load import load_results
from analysis.plots.figures_hpc import plot_weak_scaling
from analysis.plots.speedup import speedup_table
from analysis.plots.weak import fit_gustafson, weak_table

FIXTURES = Path(__file__).parent / "fixtures"


@pytest.fixture(scope="module")
def weak():
    results = load_results(FIXTURES / "analysis_weak")
    return weak_table(speedup_table(results.runs, results.cores), results.cores)


def series(weak, engine):
    return weak[weak["engine"] == engine].set_index("T")


def test_only_the_zipped_series_are_weak(weak):
    assert set(weak["engine"]) == {"brute", "cells"}


def test_weak_efficiency_and_scaled_speedup(weak):
    brute = series(weak, "brute")
    assert brute["N"].tolist() == [1000, 1414, 2000]
    assert brute["weak_efficiency"].tolist() == pytest.approx([1.0, 1.0, 0.8])
    assert brute["scaled_speedup"].tolist() == pytest.approx([1.0, 2.0, 3.2])
    cells = series(weak, "cells")
    assert cells["weak_efficiency"].tolist() == pytest.approx([1.0, 0.8, 0.8, 0.25])
    assert cells["L"].tolist() == [20000, 28284, 40000, 56569]


def test_gustafson_fit_within_the_cores(weak):
    assert series(weak, "brute")["gustafson_serial"].iloc[0] == pytest.approx(0.24)
    assert series(weak, "cells")["gustafson_serial"].iloc[0] == pytest.approx(0.28)
    assert fit_gustafson([1, 2, 4], [1, 2, 4]) == pytest.approx(0.0)
    assert fit_gustafson([1, 2], [1, 0.5]) == 1.0            # slower than serial: clamped


def test_product_sweep_has_no_weak_series():
    results = load_results(FIXTURES / "analysis_threads")
    assert weak_table(speedup_table(results.runs, results.cores)).empty


def test_weak_plot_is_drawn(weak, tmp_path):
    saved, figures.FORMATS = figures.FORMATS, ("png",)
    try:
        png = plot_weak_scaling(weak, 4, tmp_path / "weak")
        assert plot_weak_scaling(weak.iloc[0:0], 4, tmp_path / "none") is None
    finally:
        figures.FORMATS = saved
    assert png.stat().st_size > 5000


def test_cli_writes_weak_csv_plot_and_report(tmp_path):
    out = Path(shutil.copytree(FIXTURES / "analysis_weak", tmp_path / "weak"))
    done = run_tool("plots", out, "--no-svg")
    assert done.returncode == 0, done.stderr
    assert (out / "plots" / "weak_scaling.png").exists()
    assert len(pd.read_csv(out / "weak.csv")) == 7
    report = (out / "report.md").read_text()
    assert "## Weak scaling" in report
    assert "| brute | 4 | 2000 | 20000 | 1.25 | 0.8 | 3.2 | 0.24 |" in report
