"""The noise table: ratios against T=1, T=2 and the quiet minimum; bad input exits 2."""

import pandas as pd
import pytest

from analysis.common.load import InputError, normalise
from analysis.noise.cli import main, noise_table


def runs(rows):
    frame = pd.DataFrame(rows, columns=["engine", "N", "T", "neighbour", "status", "wall_s"])
    return normalise(frame)


def test_ratios_against_t1_t2_and_the_quiet_minimum():
    table = noise_table(runs([
        ["auto", 1000, 1, "none", "ok", 0.20], ["auto", 1000, 1, "none", "ok", 0.22],
        ["auto", 1000, 2, "none", "ok", 0.11], ["auto", 1000, 4, "none", "ok", 0.132],
        ["auto", 1000, 1, "busy", "ok", 0.21], ["auto", 1000, 2, "busy", "ok", 0.24],
        ["auto", 1000, 2, "busy", "ok", 0.55], ["auto", 1000, 2, "busy", "failed", 9.0],
    ]))
    row = table.set_index(["engine", "neighbour", "T"])
    assert row.loc[("auto", "none", 4), "vs_T2"] == pytest.approx(1.2)
    assert row.loc[("auto", "busy", 2), "vs_T1"] == pytest.approx(0.24 / 0.21)
    assert row.loc[("auto", "busy", 2), "worst_vs_quiet_min"] == pytest.approx(5.0)
    assert row.loc[("auto", "busy", 2), "reps"] == 2  # the failed run is not a repetition
    assert row.loc[("auto", "none", 1), "wall_s_median"] == pytest.approx(0.21)


def test_without_quiet_runs_there_is_nothing_to_compare():
    with pytest.raises(InputError, match="quiet"):
        noise_table(runs([["auto", 1000, 1, "busy", "ok", 0.2]]))


def test_missing_folder_exits_2(tmp_path, capsys):
    assert main([str(tmp_path / "absent")]) == 2
    assert "noise: error" in capsys.readouterr().err


def test_busy_and_quiet_runs_are_separate_configurations_in_the_statistics():
    from analysis.common.stats import aggregate
    table = aggregate(runs([
        ["auto", 1000, 2, "none", "ok", 0.10], ["auto", 1000, 2, "busy", "ok", 0.40],
    ]), "wall_s")
    assert sorted(table["wall_s_min"]) == [0.10, 0.40]
