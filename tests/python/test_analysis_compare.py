"""python3 -m analysis compare on two fixture sweeps written here with planted values:

  brute N=100 T=1: B is A's five repetitions in another order plus 1% jitter  -> same
  brute N=100 T=2: B is A times 1.10 (a planted 10% slow-down)                 -> slower
  brute N=200 T=1: B is A times 0.90                                           -> faster
  brute N=200 T=2: three repetitions each, ranges overlap                     -> too few to tell
  grid  N=100 T=1: one repetition each                                         -> too few to tell
  brute N=400 T=1: only in B
"""
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from entry_point import run_tool
from analysis.common.load import load_results
from analysis.common.stats import TOO_FEW, compare_samples
from analysis.compare.cli import compare_runs


FIXTURES = Path(__file__).parent / "fixtures"
NOISE = np.array([1.000, 1.021, 1.008, 1.034, 1.015])  # shared-machine noise only adds time


def write_sweep(directory: Path, rows, commit: str) -> Path:
    directory.mkdir(parents=True)
    header = (FIXTURES / "analysis_threads" / "runs.csv").read_text().splitlines()[0]
    columns = header.split(",")
    records = []
    for engine, n, t, g, walls in rows:
        for rep, wall in enumerate(walls):
            records.append(dict(engine=engine, N=n, L=1000, r=1, S=100, slow_factor=1, T=t,
                                G=g, seed=3210, pin="close", rep=rep, status="ok",
                                wall_s=repr(float(wall))))
    pd.DataFrame(records, columns=columns).to_csv(directory / "runs.csv", index=False)
    meta = json.loads((FIXTURES / "analysis_threads" / "meta.json").read_text())
    meta["git"]["commit"] = commit
    (directory / "meta.json").write_text(json.dumps(meta))
    return directory


@pytest.fixture
def sweeps(tmp_path):
    a = write_sweep(tmp_path / "old", [
        ("brute", 100, 1, "", 2.0 * NOISE),
        ("brute", 100, 2, "", 1.1 * NOISE),
        ("brute", 200, 1, "", 8.0 * NOISE),
        ("brute", 200, 2, "", [4.0, 4.2, 4.1]),
        ("grid", 100, 1, 2, [1.0]),
    ], commit="aaaaaaaaaaaa1111")
    b = write_sweep(tmp_path / "new", [
        ("brute", 100, 1, "", 2.0 * NOISE[[3, 0, 4, 1, 2]] * 1.01),
        ("brute", 100, 2, "", 1.1 * NOISE * 1.10),
        ("brute", 200, 1, "", 8.0 * NOISE * 0.90),
        ("brute", 200, 2, "", [4.15, 4.05, 4.3]),
        ("grid", 100, 1, 2, [0.7]),
        ("brute", 400, 1, "", 30.0 * NOISE),
    ], commit="bbbbbbbbbbbb2222")
    return a, b


def verdicts(table):
    return {(r.engine, int(r.N), int(r.T)): r for r in table.itertuples()}


def test_planted_change_is_flagged_and_noise_is_not(sweeps):
    a, b = (load_results(d).runs for d in sweeps)
    rows = verdicts(compare_runs(a, b))
    assert rows[("brute", 100, 1)].verdict == "same"
    assert rows[("brute", 100, 1)].test == "U test"
    assert rows[("brute", 100, 1)].p_value > 0.05
    assert rows[("brute", 100, 2)].verdict == "slower"
    assert rows[("brute", 100, 2)].p_value < 0.05
    assert rows[("brute", 100, 2)].ratio == pytest.approx(1.10)
    assert rows[("brute", 200, 1)].verdict == "faster"
    assert rows[("brute", 200, 2)].verdict == TOO_FEW
    assert rows[("brute", 200, 2)].test == "ranges"
    assert rows[("grid", 100, 1)].verdict == TOO_FEW          # one repetition: no spread
    assert rows[("grid", 100, 1)].ratio == pytest.approx(0.7)
    assert rows[("brute", 400, 1)].verdict == "only in B"
    assert rows[("brute", 400, 1)].reps_a == 0


def test_compare_samples_is_symmetric_and_needs_five_for_u():
    assert compare_samples([1.0] * 5, [2.0] * 5)[::2] == ("U test", "slower")
    assert compare_samples([2.0] * 5, [1.0] * 5)[::2] == ("U test", "faster")
    assert compare_samples([1, 2, 3, 4], [8, 9, 10, 11])[::2] == ("ranges", "slower")
    assert compare_samples([8, 9, 10, 11], [1, 2, 3, 4])[::2] == ("ranges", "faster")
    assert compare_samples([1.0], [5.0])[::2] == ("none", TOO_FEW)


def test_two_identical_sweeps_of_three_repetitions_are_not_called_slower():
    # The case: back-to-back sweeps whose ranges miss each other by 2%, each 1-2% wide.
    a, b = [1.000, 1.012, 1.018], [1.020, 1.031, 1.035]
    assert compare_samples(a, b)[::2] == ("ranges", TOO_FEW)
    # Apart by more than either range is wide: a difference 3 repetitions can show.
    assert compare_samples(a, [1.05, 1.06, 1.07])[::2] == ("ranges", "slower")


def test_cli_writes_table_plot_and_provenance(sweeps, tmp_path):
    a, b = sweeps
    out = tmp_path / "cmp"
    done = run_tool("compare", a, b, "--out", out, "--no-svg")
    assert done.returncode == 0, done.stderr
    assert (out / "ratio.png").stat().st_size > 0
    text = (out / "compare.md").read_text()
    assert text == done.stdout.rstrip("\n") + "\n\n![ratios](ratio.png)\n"
    head = text.split("|")[0]
    assert "aaaaaaaaaaaa" in head and "bbbbbbbbbbbb" in head    # both commits before the table
    assert f"1 slower, 1 faster, 1 same, 2 {TOO_FEW}" in text
    assert "1 only in B" in text
    table = pd.read_csv(out / "compare.csv")
    assert len(table) == 6 and set(table["verdict"]) >= {"slower", "faster", "same"}


def test_cli_bad_input_exits_2(sweeps, tmp_path):
    a, _ = sweeps
    done = run_tool("compare", a, tmp_path / "nowhere", timeout=60)
    assert done.returncode == 2
    assert done.stderr.startswith("compare: error: ") and "does not exist" in done.stderr
    other = write_sweep(tmp_path / "other", [("cells", 5, 1, "", [1.0])], commit="c")
    done = run_tool("compare", a, other, timeout=60)
    assert done.returncode == 2 and "no configuration in common" in done.stderr
