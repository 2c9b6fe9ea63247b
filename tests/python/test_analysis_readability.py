"""The readability fixes: time axes in s / ms / µs, log axes labelled as such, a constant series
not magnified into 0.95-1.05, and the report's measurement warnings, missing-fit reason and
provenance."""
import json
import shutil
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd
import pytest

from analysis.common import figures as common_figures
from analysis.common.load import load_results
from analysis.plots import figures
from analysis.plots.fits import fit_table
from analysis.plots.report import fits_section, provenance
from analysis.plots.sections import harness_overhead, measurement_section
from analysis.plots.speedup import speedup_table

FIXTURES = Path(__file__).parent / "fixtures"


@pytest.mark.parametrize("seconds,unit,scale", [
    ([2.0, 0.5], "s", 1.0), ([0.05, 0.002], "ms", 1e3), ([0.00005], "µs", 1e6)])
def test_time_unit_puts_the_largest_value_between_1_and_1000(seconds, unit, scale):
    assert figures.time_unit(seconds) == (unit, scale)


def test_log_axis_says_so_in_its_label():
    fig, ax = plt.subplots()
    ax.plot([1, 10, 100], [1, 10, 100])
    ax.set_ylabel("wall time (ms)")
    figures.log_if_wide(ax, [1, 100], "y")
    assert ax.get_ylabel() == "wall time (ms), log scale"
    plt.close(fig)


def test_constant_series_axis_starts_at_zero(tmp_path):
    fig, ax = plt.subplots()
    ax.plot([1, 2, 4], [1.0, 1.0, 1.0])
    common_figures.save(fig, tmp_path / "flat")
    assert ax.get_ylim() == (0.0, 2.0)         # not matplotlib's (0.945, 1.055)
    fig, ax = plt.subplots()
    ax.plot([1, 2, 4], [1.0, 1.5, 1.0])
    common_figures.save(fig, tmp_path / "varied")
    assert ax.get_ylim()[0] > 0.9              # a real variation keeps its close-up


def sweep_copy(tmp_path, scale=1.0, spread=1.0, sessions=None):
    out = Path(shutil.copytree(FIXTURES / "analysis_threads", tmp_path / "sweep"))
    runs = pd.read_csv(out / "runs.csv")
    runs["wall_s"] = runs["wall_s"] * scale
    if spread != 1.0:  # three more repetitions per configuration, the last two slower
        extra = [runs.assign(rep=runs["rep"] + k, wall_s=runs["wall_s"] * f)
                 for k, f in [(10, 1.0), (20, spread), (30, spread)]]
        runs = pd.concat([runs] + extra)
    runs.to_csv(out / "runs.csv", index=False)
    meta = json.loads((out / "meta.json").read_text())
    if sessions is not None:
        meta["sessions"] = sessions
    (out / "meta.json").write_text(json.dumps(meta))
    results = load_results(out)
    return results, speedup_table(results.runs, results.cores, results.declaration)


def test_short_runs_are_warned_about_with_the_harness_overhead(tmp_path):
    sessions = [{"sweep_wall_s": 1.22, "children_process_s": 1.0, "overhead": 0.22}]
    results, table = sweep_copy(tmp_path, scale=1e-4, sessions=sessions)
    text = measurement_section(results, table)
    assert "Runs too short to measure well" in text
    assert "12 of 12 configurations ran for under 1 ms (the shortest 40 µs)" in text
    assert "The harness itself cost 22%" in text
    assert "machine was busy" not in text


def test_clean_sweep_has_no_warnings(tmp_path):
    results, table = sweep_copy(tmp_path, sessions=[{"sweep_wall_s": 10.1,
                                                     "children_process_s": 10.0}])
    assert measurement_section(results, table) == ""


def test_wide_spread_of_repetitions_says_the_machine_was_busy(tmp_path):
    results, table = sweep_copy(tmp_path, spread=1.5)
    text = measurement_section(results, table)
    assert "The machine was busy" in text
    _, quiet = sweep_copy(tmp_path / "quiet", spread=1.02)
    assert "busy" not in measurement_section(results, quiet)


def test_harness_overhead_sums_sessions():
    meta = {"sessions": [{"sweep_wall_s": 11, "children_process_s": 10},
                         {"sweep_wall_s": 33, "children_process_s": 30}]}
    assert harness_overhead(meta) == pytest.approx(0.1)
    assert harness_overhead({"sessions": [{"overhead": 0.3}]}) == 0.3
    assert harness_overhead({}) is None


def test_report_says_why_a_power_law_fit_is_missing():
    table = speedup_table(load_results(FIXTURES / "analysis_threads").runs)
    text = fits_section(fit_table(table))   # N in {100, 200}: two points per series
    assert "No power-law fit" in text and "at most 2 distinct values" in text
    assert "a fit needs 3" in text


def test_provenance_is_short_and_tables_what_the_sweep_used():
    """meta.json's essentials as short lines, the engines and metrics the sweep used as tables;
    the declaration, the config and absolute paths stay in meta.json."""
    results = load_results(FIXTURES / "analysis_threads")
    text = provenance(results)
    assert max(len(line) for line in text.splitlines()) < 200
    for line in ["- date: 2024-01-01T00:00:00Z", "- commit: `0123456789abcdef`",
                 "- machine: fixture, Fixture CPU @ 2.0GHz; 2 CPUs, 2 cores; Linux 6.1.0, x86_64",
                 "- compiler: GNU 12.2.0 `-O3 -march=native` (Release); OpenMP GNU libgomp 201511",
                 "- counters: software (no hardware counters on this VM)",
                 "- command: `build/psweep configs/fixture.json`"]:
        assert line + "\n" in text
    assert "/work/main" not in text and "extra_key" not in text and "fixture-threads" not in text
    engines = text.split("### Engines the sweep ran")[1].split("###")[0]
    assert "| brute | yes | yes | T, K |" in engines and "| grid |" in engines
    assert "| auto |" not in engines                      # declared, but the sweep never ran it
    metrics = text.split("### Metrics psim reported")[1]
    assert "| pair_tests | counter | 1 |" in metrics
    assert "max_overlap" not in metrics                   # declared, no value in any run
    assert "`meta.json`" in text
    results.meta["command_line"] = ["build/psweep", "my config.json", "--out", "results/x"]
    assert "- command: `build/psweep 'my config.json' --out results/x`\n" in provenance(results)


def test_provenance_without_meta_says_so(tmp_path):
    out = Path(shutil.copytree(FIXTURES / "analysis_threads", tmp_path / "sweep"))
    (out / "meta.json").unlink()
    assert "provenance unknown" in provenance(load_results(out))
