"""Every plot function draws a non-empty PNG from the fixture, and declines (returns None)
instead of drawing an empty plot when its data is absent."""
from pathlib import Path

import pandas as pd
import pytest

from analysis.common import figures as common_figures
from analysis.common.load import load_results
from analysis.common.stats import aggregate, record_runs
from analysis.plots import figures
from analysis.plots.speedup import speedup_table

FIXTURES = Path(__file__).parent / "fixtures"


@pytest.fixture(scope="module", autouse=True)
def png_only():
    saved, common_figures.FORMATS = common_figures.FORMATS, ("png",)  # SVG doubles the time, adds nothing
    yield
    common_figures.FORMATS = saved


@pytest.fixture(scope="module")
def results():
    return load_results(FIXTURES / "analysis_threads")


@pytest.fixture(scope="module")
def table(results):
    return speedup_table(results.runs, declaration=results.declaration)


def assert_png(path):
    assert path is not None and path.suffix == ".png"
    data = path.read_bytes()
    assert len(data) > 5000 and data[:8] == b"\x89PNG\r\n\x1a\n"


def test_thread_count_plots(table, tmp_path):
    brute = table[table["engine"] == "brute"]
    assert_png(figures.plot_speedup(brute, 2, tmp_path / "speedup"))
    assert_png(figures.plot_efficiency(brute, 2, tmp_path / "efficiency"))
    assert_png(figures.plot_wall_time(brute, None, tmp_path / "wall"))   # cores unknown
    assert_png(figures.plot_speedup(table, 2, tmp_path / "vs_brute", column="speedup_vs_brute",
                                    title="Speed-up over brute"))


def test_counter_plot(results, tmp_path):
    panels = {"voluntary": aggregate(results.runs, "voluntary_switches"),
              "involuntary": aggregate(results.runs, "involuntary_switches")}
    assert_png(figures.plot_counter_vs_threads(panels, 2, tmp_path / "cs", "t", "switches"))


def test_counter_plot_declines_when_counters_are_empty(results, tmp_path):
    # cycles is empty on this VM-like fixture
    assert figures.plot_counter_vs_threads({"cycles": aggregate(results.runs, "cycles")},
                                           2, tmp_path / "cycles", "t", "cycles") is None


def test_scaling_plot(tmp_path):
    oat = load_results(FIXTURES / "analysis_oat")
    table = speedup_table(oat.runs, declaration=oat.declaration)
    assert_png(figures.plot_scaling(table, "N", tmp_path / "scaling_N"))


def test_a_grid_size_study_shows_the_engines_it_competes_with(table, tmp_path):
    """scaling_G: grid against G, and brute (which has no G) at the same scene and T as a level
    line of the series' colour, tagged for its tooltip; without brute's runs, grid alone."""
    from analysis.common.hover import read_positions
    png = figures.plot_scaling(table, "G", tmp_path / "scaling_G")
    assert_png(png)
    # A tooltip names every point on its spot, a line each.
    tips = [line for p in read_positions(png) for line in p["text"].splitlines()]
    brute = sorted(t.split("T=")[1].split(",")[0] for t in tips if t.startswith("engine=brute"))
    assert brute == ["1", "2", "4"]  # one line per thread count of grid's series
    assert all("N=100," in t for t in tips)  # brute's N=200 runs are another scene
    alone = figures.plot_scaling(table[table["engine"] == "grid"], "G", tmp_path / "alone")
    assert not any("engine=brute" in p["text"] for p in read_positions(alone))


def test_stage_plot(results, tmp_path):
    stages = results.declaration.stage_columns
    assert_png(figures.plot_stage_times(record_runs(results.runs), tmp_path / "stages", stages))
    no_stages = record_runs(results.runs).assign(**{c: float("nan") for c in stages})
    assert figures.plot_stage_times(no_stages, tmp_path / "none", stages) is None


def test_thread_plots_decline_single_thread_count(table, tmp_path):
    only_t1 = table[table["T"] == 1]
    assert figures.plot_speedup(only_t1, 2, tmp_path / "s") is None
    assert figures.plot_wall_time(only_t1, 2, tmp_path / "w") is None
    assert not list(tmp_path.iterdir())


def test_svg_written_next_to_png(table, tmp_path):
    common_figures.FORMATS = ("png", "svg")
    try:
        png = figures.plot_speedup(table[table["engine"] == "grid"], 2, tmp_path / "g")
    finally:
        common_figures.FORMATS = ("png",)
    assert png.with_suffix(".svg").stat().st_size > 0
