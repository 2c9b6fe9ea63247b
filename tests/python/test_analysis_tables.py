"""Optimal thread count / peak speed-up tables, failure accounting and hash agreement."""
from pathlib import Path

import pandas as pd
import pytest

from analysis.common.load import load_results, normalise, status_counts
from analysis.plots.speedup import speedup_table
from analysis.plots.tables import failure_table, hash_agreement, peak_table

FIXTURES = Path(__file__).parent / "fixtures"


@pytest.fixture(scope="module")
def results():
    return load_results(FIXTURES / "analysis_threads")


@pytest.fixture(scope="module")
def peaks(results):
    return peak_table(speedup_table(results.runs, declaration=results.declaration))


def peak(peaks, engine, n, g=None):
    match = (peaks["engine"] == engine) & (peaks["N"] == n)
    match &= peaks["G"].isna() if g is None else (peaks["G"] == g)
    assert match.sum() == 1
    return peaks[match].iloc[0]


def test_optimal_T_is_not_simply_the_largest(peaks):
    # brute N=100 is fastest at T=2 (2.0x); T=4 only reaches 1.6x.
    p = peak(peaks, "brute", 100)
    assert p["optimal_T"] == 2
    assert p["peak_speedup"] == pytest.approx(2.0)
    assert p["efficiency"] == pytest.approx(1.0)
    assert p["wall_s_T1"] == pytest.approx(2.0)
    assert p["wall_s_best"] == pytest.approx(1.0)


def test_peak_per_N_and_per_G(peaks):
    assert len(peaks) == 4
    p = peak(peaks, "brute", 200)
    assert (p["optimal_T"], p["peak_speedup"]) == (4, pytest.approx(3.2))
    for g, best_wall in [(2, 0.5), (4, 0.4)]:
        p = peak(peaks, "grid", 100, g)
        assert p["optimal_T"] == 4
        assert p["peak_speedup"] == pytest.approx(2.0)
        assert p["wall_s_best"] == pytest.approx(best_wall)


def test_ties_go_to_fewer_threads():
    runs = normalise(pd.DataFrame([
        dict(engine="brute", N=10, T=t, status="ok", wall_s=w)
        for t, w in [(1, 4.0), (2, 2.0), (4, 2.0)]]))
    assert peak_table(speedup_table(runs)).iloc[0]["optimal_T"] == 2


def test_failure_accounting(results):
    assert status_counts(results.runs) == {"failed": 1, "ok": 20, "timeout": 1}
    failed = failure_table(results.runs)
    assert sorted(failed["status"]) == ["failed", "timeout"]
    assert "error" in failed.columns


def test_hash_agreement_detects_a_disagreeing_run(results):
    table = hash_agreement(results.runs)
    assert (table["distinct_hashes"] == 1).all()
    broken = results.runs.copy()
    broken.loc[broken.index[0], "state_hash"] = "different"
    table = hash_agreement(broken)
    assert (table["distinct_hashes"] > 1).sum() == 1


def test_cpu_share_flags_a_busy_machine():
    from analysis.plots.tables import cpu_share
    runs = normalise(pd.DataFrame([
        # T=1 got 1.3 s of CPU in 2.0 s: 65 % of a core, other processes took the rest.
        dict(engine="brute", N=10, T=1, status="ok", wall_s=2.0, process_s=2.0, user_s=1.2,
             sys_s=0.1),
        # T=4 on 2 cores: 3.0 s of CPU in 1.5 s is both cores fully used.
        dict(engine="brute", N=10, T=4, status="ok", wall_s=1.5, process_s=1.5, user_s=2.9,
             sys_s=0.1),
        dict(engine="brute", N=10, T=4, status="failed", wall_s="", process_s=0.1, user_s=0,
             sys_s=0),
    ]))
    table = cpu_share(runs, cores=2).set_index("T")
    assert table.loc[1, "cpu_share"] == pytest.approx(0.65)
    assert table.loc[4, "cpu_share"] == pytest.approx(1.0)
    assert table.loc[4, "runs"] == 1


def test_cpu_share_of_ranks_counts_every_ranks_threads():
    from analysis.plots.tables import cpu_share
    runs = normalise(pd.DataFrame([
        # P = 2 ranks of T = 1 on 2 cores: 2 s of CPU in 1 s is both cores, not twice one.
        dict(engine="mpi", N=10, P=2, T=1, status="ok", wall_s=0.9, process_s=1.0, user_s=1.9,
             sys_s=0.1),
        dict(engine="brute", N=10, T=1, status="ok", wall_s=1.0, process_s=1.0, user_s=1.0,
             sys_s=0.0),
    ]))
    table = cpu_share(runs, cores=2)
    mpi = table[table["engine"] == "mpi"].iloc[0]
    assert mpi["P"] == 2 and mpi["cpu_share"] == pytest.approx(1.0)
    brute = table[table["engine"] == "brute"].iloc[0]
    assert pd.isna(brute["P"]) and brute["cpu_share"] == pytest.approx(1.0)


def test_hash_agreement_holds_only_engines_declared_to_match_the_reference(results):
    # an engine declared not to match the reference (a different dynamics, or one that drops
    # collisions on purpose) may disagree; one declared to match may not
    declared = results.declaration
    other = results.runs[results.runs["engine"] == "grid"].assign(engine="approx",
                                                                  state_hash="other")
    runs = pd.concat([results.runs, other], ignore_index=True)
    assert (hash_agreement(runs, declared.exact_engines)["distinct_hashes"] == 1).all()
    assert (hash_agreement(runs, declared.exact_engines | {"approx"})["distinct_hashes"] > 1).any()
    assert "grid-unsafe" not in declared.exact_engines and "brute" in declared.exact_engines
