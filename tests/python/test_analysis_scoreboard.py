"""The scoreboard (analysis/scoreboard) on the hand-written fixture fixtures/analysis_programs:
one scene (N=40), the engines brute and auto (both declared to match the reference) and four
external programs, whose expected rows were worked out by hand:

  auto        exact (engine)  T=1 0.20, best 0.12 at T=2
  brute       exact (engine)  T=1 0.50 (min of 0.50, 0.55), best 0.30 at T=2
  good        exact at T=1, consistent at T=2: consistent; T=1 0.40, best 0.25 at T=2
  crash       no ok run: unchecked, no times
  fast_wrong  violations at time unit 3, 0.05 s: the fastest, ranked below every correct one
  garbage     malformed, 0.01 s: last
"""
import math
from pathlib import Path

import pytest

from analysis.common.declaration import Declaration
from analysis.common.load import load_results
from analysis.plots.report import scoreboard_section
from analysis.plots.speedup import speedup_table
from analysis.scoreboard.board import scoreboard
from entry_point import run_tool

FIXTURE = Path(__file__).parent / "fixtures" / "analysis_programs"


@pytest.fixture(scope="module")
def results():
    return load_results(FIXTURE)


@pytest.fixture(scope="module")
def board(results):
    return scoreboard(results.runs, results.programs, results.declaration)


def test_sorted_by_verdict_then_speed(board):
    assert list(board["name"]) == ["auto", "brute", "good", "crash", "fast_wrong", "garbage"]
    assert list(board["rank"]) == [1, 2, 3, 4, 5, 6]
    assert list(board["verdict"]) == ["exact", "exact", "consistent", "unchecked", "violations",
                                      "malformed"]
    assert list(board["kind"]) == ["engine", "engine"] + ["program"] * 4
    assert set(board["scene"]) == {"N=40 L=2000 r=1 S=20 K=1 seed=7"}


def test_times_speedups_and_the_fastest_exact_engine(board):
    row = board.set_index("name")
    assert row.loc["brute", "time_T1_s"] == 0.50
    assert row.loc["good", "time_T1_s"] == 0.40
    assert row.loc["good", "best_s"] == 0.25 and row.loc["good", "best_T"] == 2
    assert row.loc["good", "speedup"] == pytest.approx(1.6)
    assert row.loc["good", "vs_fastest_exact"] == pytest.approx(0.12 / 0.25)
    assert row.loc["fast_wrong", "vs_fastest_exact"] == pytest.approx(0.12 / 0.05)
    assert math.isnan(row.loc["crash", "best_s"])


def test_the_first_violation_is_named(board):
    row = board.set_index("name")
    assert row.loc["fast_wrong", "first_violation"].startswith(
        "2 violations; the first at time unit 3: energy not conserved")
    assert row.loc["garbage", "first_violation"] == "line 1: expected 5 fields"
    assert row.loc["good", "first_violation"] == ""


def test_every_unchecked_row_says_why(results, board):
    assert board.set_index("name").loc["crash", "first_violation"] == "no ok run: 1 crashed"
    runs = results.runs.copy()
    good = runs["engine"] == "good"
    runs.loc[good, "check"] = "error"
    runs.loc[good, "check_detail"] = "psim check timed out after 60 s"
    row = scoreboard(runs, results.programs, results.declaration).set_index("name")
    assert (row.loc["good", "verdict"], row.loc["good", "first_violation"]) == (
        "unchecked", "psim check could not judge it (error): psim check timed out after 60 s")
    runs.loc[good, "check"] = None
    row = scoreboard(runs, results.programs, results.declaration).set_index("name")
    assert row.loc["good", "first_violation"] == "no check recorded for its runs"
    # Engines: judged by psim's declaration, or said to be not judged and why.
    inexact = Declaration(engines=[{"name": "brute", "matches_reference": True}])
    row = scoreboard(results.runs, results.programs, inexact).set_index("name")
    assert row.loc["brute", "verdict"] == "exact"
    assert (row.loc["auto", "verdict"], row.loc["auto", "first_violation"]) == (
        "unchecked", "psim declares it not bit-identical to the reference")
    row = scoreboard(results.runs, results.programs, Declaration()).set_index("name")
    assert row.loc["brute", "first_violation"] == (
        "meta.json has no psim declaration to say it is exact")
    assert (row[row["verdict"] == "unchecked"]["first_violation"] != "").all()


def test_a_program_is_timed_against_the_reference_as_a_whole_process(results):
    table = speedup_table(results.runs, results.cores, results.declaration, results.programs)
    good = table[(table["engine"] == "good") & (table["T"] == 2)].iloc[0]
    assert good["speedup"] == pytest.approx(0.40 / 0.25)
    assert good["efficiency"] == pytest.approx(0.8)
    assert good["karp_flatt"] == pytest.approx((1 / 1.6 - 1 / 2) / (1 - 1 / 2))
    assert good["speedup_vs_brute"] == pytest.approx(0.50 / 0.25)  # brute's process, not loop
    auto = table[(table["engine"] == "auto") & (table["T"] == 2)].iloc[0]
    assert auto["speedup_vs_brute"] == pytest.approx(0.45 / 0.10)  # engines: the loop times


def test_report_section_only_with_programs(results):
    section = scoreboard_section(results)
    assert section.startswith("\n## Scoreboard\n")
    assert "| 5 | fast_wrong | program | violations |" in section
    results_without = load_results(FIXTURE)
    results_without.meta = {k: v for k, v in results.meta.items() if k != "programs"}
    assert scoreboard_section(results_without) == ""


def test_command_line_writes_the_csv(tmp_path):
    for name in ("runs.csv", "meta.json"):
        (tmp_path / name).write_text((FIXTURE / name).read_text())
    done = run_tool("scoreboard", tmp_path)
    assert done.returncode == 0, done.stderr
    assert "| 1 | auto | engine | exact |" in done.stdout
    lines = (tmp_path / "scoreboard.csv").read_text().splitlines()
    assert lines[0] == ("scene,rank,name,kind,verdict,first_violation,time_T1_s,best_s,best_T,"
                        "speedup,vs_fastest_exact")
    assert len(lines) == 7
    missing = run_tool("scoreboard", tmp_path / "nothing")
    assert missing.returncode == 2 and "does not exist" in missing.stderr
