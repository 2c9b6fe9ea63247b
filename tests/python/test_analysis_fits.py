"""Power-law fits: exponent recovered from synthetic data, series selection in one-at-a-time
sweeps."""
from pathlib import Path

import numpy as np
import pytest

from analysis.common.load import load_results
from analysis.plots.fits import fit_power_law, fit_table, scaling_params
from analysis.plots.speedup import speedup_table

FIXTURES = Path(__file__).parent / "fixtures"


def test_quadratic_data_gives_exponent_two():
    n = np.array([250, 500, 1000, 2000, 4000])
    rng = np.random.default_rng(3210)
    t = 3e-7 * n ** 2 * rng.uniform(0.97, 1.03, len(n))  # +-3 % timing noise
    fit = fit_power_law(n, t)
    assert fit.exponent == pytest.approx(2.0, abs=0.05)
    assert fit.r_squared > 0.99
    assert fit(1000) == pytest.approx(0.3, rel=0.1)


def test_flat_data_gives_exponent_zero():
    fit = fit_power_law([500, 1000, 2000, 4000], [1.0, 1.01, 0.99, 1.0])
    assert abs(fit.exponent) < 0.02


def test_too_few_points_claims_no_exponent():
    assert fit_power_law([100, 200], [1.0, 4.0]) is None
    assert fit_power_law([100, 200, 0], [1.0, 4.0, 0.0]) is None   # non-positive dropped


def test_one_at_a_time_sweep_fits_each_axis_through_the_base():
    oat = load_results(FIXTURES / "analysis_oat")
    table = speedup_table(oat.runs, declaration=oat.declaration)
    assert scaling_params(table) == ["N", "L", "r"]
    fits = fit_table(table).set_index("parameter")
    assert fits.loc["N", "points"] == 4
    assert fits.loc["N", "exponent"] == pytest.approx(2.0, abs=1e-6)
    assert abs(fits.loc["L", "exponent"]) < 0.1
    assert abs(fits.loc["r", "exponent"]) < 0.1
    # The L series holds N and r at the base point.
    assert (fits.loc["L", "N"], fits.loc["L", "r"]) == (200, 1)
