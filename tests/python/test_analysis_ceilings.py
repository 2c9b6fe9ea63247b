"""Each configuration against the machine's ceilings (analysis/plots/ceilings.py), on a hand-made
sweep and hand-made ceilings: a brute whose loop is all pair tests at half the peak, an engine that
spends its loop elsewhere, one whose process is mostly start-up, and T = 2 against a machine whose
kernel gains only 1.35x from its second CPU."""
import pandas as pd
import pytest

from analysis.common.load import normalise
from analysis.plots.ceilings import STATE_BYTES, Ceilings, add_ceilings, binding_sentence
from analysis.plots.figures_hpc import plot_ceilings
from analysis.plots.sections import ceilings_section
from analysis.plots.speedup import speedup_table


def spread(value):
    return {"min": value, "median": value, "max": value, "repetitions": 3}


META = {"ceilings": {
    "cpus": 2,
    "pair_kernel": {"T1": {"ns_per_pair_test": spread(0.1)},
                    "Tall": {"ns_per_pair_test": spread(0.1 / 1.35)}},
    "bandwidth": {"triad": {"T1": {"gb_per_s": spread(10.0)}, "Tall": {"gb_per_s": spread(16.0)}}},
    "startup": {"process_s": spread(0.002), "omp_team_s": spread(0.0003)},
    "loadavg_before": "0.42 0.50 0.61 1/300 1234"}}


def row(engine, n, t, wall, pairs, process):
    return dict(engine=engine, N=n, L=1000, r=1, S=10, slow_factor=1, T=t, seed="1", pin="close",
                status="ok", wall_s=wall, process_s=process, pair_tests=pairs, engine_ran=engine)


@pytest.fixture(scope="module")
def table():
    rows = [row("brute", 1000, 1, 0.1, 5e8, 0.105),      # 0.2 ns per pair test: half the peak
            row("brute", 1000, 2, 0.1 / 1.2, 5e8, 0.09),  # 1.2x of the machine's 1.35x
            row("cells", 1000, 1, 0.05, 1e6, 0.055),       # 50 ns per pair test
            row("tiny", 10, 1, 0.0001, 500, 0.003)]        # the loop 3% of its process
    return speedup_table(normalise(pd.DataFrame(rows)), ceilings=Ceilings.from_meta(META))


def at(table, engine, t):
    return table[(table["engine"] == engine) & (table["T"] == t)].iloc[0]


def test_shares_of_each_ceiling(table):
    brute = at(table, "brute", 1)
    assert brute["pair_peak_pct"] == pytest.approx(50)
    # 48 bytes at 10 GB/s = 4.8 ns against 1e8 ns / (1000 x 10) particle-steps
    assert brute["bandwidth_pct"] == pytest.approx(100 * STATE_BYTES / 10 / 1e4)
    assert brute["loop_share_pct"] == pytest.approx(100 * 0.1 / 0.105)
    two = at(table, "brute", 2)
    assert two["pair_peak_pct"] == pytest.approx(100 * (0.1 / 1.35) / (1e9 * 0.1 / 1.2 / 5e8))
    assert two["scaling_vs_machine"] == pytest.approx(1.2 / 1.35)


def test_a_machine_between_one_and_all_cpus_is_interpolated():
    c = Ceilings(cpus=4, pair_rate=(1.0, 3.0), bandwidth=(1.0, 1.0), process_start_s=0,
                 team_start_s=0)
    assert list(c.kernel_ratio([1, 2, 4, 8])) == pytest.approx([1, 5 / 3, 3, 3])


def test_one_sentence_per_engine_names_the_ceiling(table):
    c = Ceilings.from_meta(META)
    brute = binding_sentence("brute", table[table["engine"] == "brute"], c)
    assert "bound by the pair kernel's peak: 50%" in brute
    assert "T = 2 gives 1.20x, 89% of the 1.35x" in brute
    assert "share a core's vector units" in brute  # 1.35x on 2 CPUs: the machine's own ceiling
    def sentence(engine):
        return binding_sentence(engine, table[table["engine"] == engine], c)
    assert "no ceiling measured here" in sentence("cells")
    assert "start-up and I/O: its loop is 3%" in sentence("tiny")


def test_report_section(table):
    text = ceilings_section(table, Ceilings.from_meta(META))
    assert text.count("\n- **") == 3
    assert "% of pair peak" in text and "at load average 0.42" in text
    assert "no ceilings" in ceilings_section(table, Ceilings.from_meta({}))


def test_without_ceilings_the_columns_are_empty():
    rows = [row("brute", 100, 1, 0.01, 5000, 0.02)]
    table = speedup_table(normalise(pd.DataFrame(rows)))
    assert table[["pair_peak_pct", "bandwidth_pct", "scaling_vs_machine"]].isna().all().all()


def test_figure(table, tmp_path):
    two_sizes = table.copy()
    two_sizes.loc[two_sizes["engine"] == "tiny", "engine"] = "brute"  # brute at N = 10 and 1000
    png = plot_ceilings(two_sizes, tmp_path / "ceilings")
    assert png is not None and png.exists() and png.stat().st_size > 0
    assert plot_ceilings(table[table["N"] == 1000], tmp_path / "one") is None  # a single N
    empty = table.assign(pair_peak_pct=float("nan"), bandwidth_pct=float("nan"))
    assert plot_ceilings(empty, tmp_path / "none") is None  # no ceilings recorded
