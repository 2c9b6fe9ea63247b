"""Which engine wins where, and whether auto picked it: a hand-made sweep where brute wins at
N=100 (auto picked sweep: a miss), sweep wins at N=1000 (auto picked sweep: a hit), and the
inexact event engine is fastest everywhere but must not count when psim declares it inexact."""

import itertools
import json
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from build_path import BUILD
from analysis.common import figures
from analysis.common.load import normalise
from analysis.plots.cost import auto_versus_fastest, picking_engines
from analysis.plots.figures_hpc import plot_cost_per_step
from analysis.plots.sections import cost_section
from analysis.plots.speedup import speedup_table

WALLS = {("brute", 100): 0.01, ("sweep", 100): 0.02, ("auto", 100): 0.021,
         ("brute", 1000): 1.0, ("sweep", 1000): 0.2, ("auto", 1000): 0.19,
         ("event", 100): 0.001, ("event", 1000): 0.01}


@pytest.fixture(scope="module")
def table():
    rows = [dict(engine=e, N=n, L=1000, r=1, S=10, slow_factor=1, T=1, seed="3210",
                 pin="close", status="ok", wall_s=w, pair_tests=n * n * 5,
                 engine_ran="auto:sweep" if e == "auto" else e)
            for (e, n), w in WALLS.items()]
    return speedup_table(normalise(pd.DataFrame(rows)))


def test_auto_is_the_engine_that_picks(table):
    assert picking_engines(table) == {"auto"}


def test_fastest_exact_engine_and_auto_choice(table):
    contests = auto_versus_fastest(table, exact_engines={"brute", "sweep"}).set_index("N")
    assert contests.loc[100, "fastest"] == "brute"
    assert contests.loc[100, "picked"] == "sweep"
    assert not contests.loc[100, "picked_is_fastest"]
    assert contests.loc[100, "picked_wall_s"] / contests.loc[100, "fastest_wall_s"] == \
        pytest.approx(2.1)
    assert contests.loc[1000, "fastest"] == "sweep" and contests.loc[1000, "picked_is_fastest"]
    assert contests.loc[1000, "engines"] == 2


def test_without_a_declaration_every_engine_competes(table):
    assert set(auto_versus_fastest(table)["fastest"]) == {"event"}


def test_ns_per_particle_step_column(table):
    brute = table[(table["engine"] == "brute") & (table["N"] == 1000)].iloc[0]
    assert brute["ns_per_particle_step"] == pytest.approx(1e9 * 1.0 / (1000 * 10))
    assert brute["ns_per_pair_test"] == pytest.approx(1e9 * 1.0 / 5e6)


def test_tests_per_needed_pair_is_the_broad_phases_excess():
    # brute tests every pair, sweep a tenth of them; both find the same 50 pairs that can collide.
    rows = [dict(engine=e, N=1000, L=1000, r=1, S=10, slow_factor=1, T=1, seed="3210",
                 pin="close", status="ok", wall_s=1.0, pair_tests=tests, pair_candidates=50,
                 engine_ran=e) for e, tests in (("brute", 5_000_000), ("sweep", 500_000))]
    rows.append({**rows[0], "engine": "event", "engine_ran": "event", "pair_candidates": 0})
    table = speedup_table(normalise(pd.DataFrame(rows))).set_index("engine")
    assert table.loc["brute", "tests_per_needed_pair"] == pytest.approx(100_000)
    assert table.loc["sweep", "tests_per_needed_pair"] == pytest.approx(10_000)
    assert pd.isna(table.loc["event", "tests_per_needed_pair"])  # no pair candidates counted


def test_builds_per_substep_from_the_counts():
    # K = 4 over 10 time units: sweep builds every sub-step, cells in 4 of the 40, brute none; a
    # run interrupted after 5 time units counts its own sub-steps; a program counts nothing.
    rows = [dict(engine=e, N=1000, L=1000, r=1, S=10, slow_factor=4, T=1, seed="3210",
                 pin="close", status="ok", wall_s=1.0, broad_phase_builds=builds,
                 time_reached=reached, engine_ran=e)
            for e, builds, reached in (("sweep", 40, 10), ("cells", 4, 10), ("brute", 0, 10),
                                       ("bands", 20, 5), ("prog", None, None))]
    table = speedup_table(normalise(pd.DataFrame(rows))).set_index("engine")
    assert table.loc["sweep", "builds_per_substep"] == pytest.approx(1)
    assert table.loc["cells", "builds_per_substep"] == pytest.approx(0.1)
    assert table.loc["brute", "builds_per_substep"] == 0
    assert table.loc["bands", "builds_per_substep"] == pytest.approx(1)
    assert pd.isna(table.loc["prog", "builds_per_substep"])


def test_report_section_and_plot(table, tmp_path):
    contests = auto_versus_fastest(table, exact_engines={"brute", "sweep"})
    text = cost_section(contests)
    assert "| 100 | 1 | 2 | brute | 0.01 | auto | sweep | no | 2.1 |" in text
    assert "1 of 2 judged choices were not the fastest" in text
    assert "cannot be judged" not in text
    saved, figures.FORMATS = figures.FORMATS, ("png",)
    try:
        png = plot_cost_per_step(table, contests, tmp_path / "cost")
    finally:
        figures.FORMATS = saved
    assert png is not None and png.stat().st_size > 5000
    assert plot_cost_per_step(table[table["N"] == 100], contests, tmp_path / "one") is None


def test_a_pick_whose_engine_was_not_swept_is_not_judged(table):
    # Only brute beside auto: auto's pick (sweep) was never timed on its own, so whether it was
    # the fastest is unknown, and the report says what to add instead of calling it a miss.
    without_sweep = table[table["engine"] != "sweep"]
    contests = auto_versus_fastest(without_sweep, exact_engines={"brute", "sweep"})
    assert list(contests["picked_measured"]) == [False, False]
    assert contests["picked_is_fastest"].isna().all()
    text = cost_section(contests)
    assert "| not judged: sweep not swept on its own here |" in text
    assert "2 choices cannot be judged" in text and "(sweep)" in text
    # auto alone: nothing to compare with, still said.
    alone = auto_versus_fastest(table[table["engine"] == "auto"], exact_engines={"brute"})
    assert len(alone) == 2 and (alone["engines"] == 0).all()
    assert "cannot be judged" in cost_section(alone)


def test_a_pick_of_several_engines_says_why_it_is_not_judged(table):
    # auto switched from cells to sweep during the run at N=1000: no one engine's time to judge
    # it by, whatever was swept, and nothing to add to the config.
    switched = table.assign(engine_ran=table["engine_ran"].where(
        ~((table["engine"] == "auto") & (table["N"] == 1000)), "auto:cells+sweep"))
    contests = auto_versus_fastest(switched, exact_engines={"brute", "sweep"}).set_index("N")
    assert contests.loc[100, "not_judged"] == ""
    assert contests.loc[1000, "not_judged"] == (
        "ran cells+sweep in turn: no one engine to time it against")
    text = cost_section(contests.reset_index())
    assert "| not judged: ran cells+sweep in turn: no one engine to time it against |" in text
    assert "cannot be judged" not in text


@pytest.mark.skipif(not (BUILD / "psim").is_file(), reason="no psim: make build")
def test_the_quick_sweep_judges_every_pick_of_auto(tmp_path):
    """make sweep's default config sweeps on their own the engines auto picks on its scenes, so
    its "which engine wins where" judges every pick instead of reading `not judged` throughout
    (issue 42: it had swept brute and auto only, and auto picks sweep)."""
    config = json.loads((Path(__file__).resolve().parents[2] / "configs" / "quick.json").read_text())
    swept, base = config["sweep"], config["base"]
    picks = set()
    for n, t in itertools.product(swept["N"], swept["T"]):
        header = f"{n}\n{base['L']}\n{base['r']}\n{base['S']}\nperf\n"
        metrics = tmp_path / f"{n}_{t}.json"
        done = subprocess.run([str(BUILD / "psim"), "--threads", str(t), "--seed",
                               str(base["seed"]), "--metrics", str(metrics)], input=header,
                              capture_output=True, text=True, timeout=60)
        assert done.returncode == 0, done.stderr
        picks |= set(json.loads(metrics.read_text())["engine"].split(":")[1].split("+"))
    assert picks and "auto" in swept["engine"]
    assert picks <= set(swept["engine"]), f"auto picks {picks}, quick.json sweeps {swept['engine']}"
