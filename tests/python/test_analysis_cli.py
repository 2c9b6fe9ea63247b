"""`python3 -m analysis plots DIR` end to end, as `make plots` runs it: outputs on good input, exit 2
with one clear line and no traceback on bad input."""
import shutil
from pathlib import Path

import pandas as pd
import pytest

from entry_point import run_tool

FIXTURES = Path(__file__).parent / "fixtures"


def run(*args):
    return run_tool("plots", *args)


def copy(name, tmp_path):
    return Path(shutil.copytree(FIXTURES / name, tmp_path / name))


def test_help():
    done = run("--help")
    assert done.returncode == 0 and "DIR" in done.stdout


def test_threads_sweep_end_to_end(tmp_path):
    out = copy("analysis_threads", tmp_path)
    done = run(out, "--no-svg")
    assert done.returncode == 0, done.stderr
    speedup = pd.read_csv(out / "speedup.csv")
    assert len(speedup) == 12
    pngs = {p.name for p in (out / "plots").glob("*.png")}
    for name in ["speedup_brute.png", "wall_time_brute.png", "efficiency_brute.png",
                 "speedup_grid.png", "speedup_vs_brute.png", "context_switches_brute.png",
                 "stage_times_grid.png", "karp_flatt_brute.png", "karp_flatt_grid.png",
                 "cost_per_particle_step.png"]:
        assert name in pngs
    report = (out / "report.md").read_text()
    assert "0123456789abcdef" in report                     # provenance
    assert "1 failed, 1 timeout" in report                  # failed runs counted
    assert "| 100 | 2 | 2 | 1 | 2 | 1 |" in report          # brute N=100: optimal T=2, peak 2
    for png in pngs:                                        # every plot embedded, relative
        assert f"](plots/{png})" in report
    assert "machine was busy" not in report                 # fixture CPU times are clean
    assert "| 2 | 0.2 | 0.2 | 0.333 |" in report            # grid G=2: Amdahl f, e at T=2, 4
    assert "No power-law fit" in report                     # N in {100, 200}: says why
    assert {"karp_flatt", "amdahl_f", "ns_per_particle_step"} <= set(speedup.columns)


def test_busy_machine_is_reported(tmp_path):
    out = copy("analysis_threads", tmp_path)
    runs = pd.read_csv(out / "runs.csv")
    runs["user_s"] = runs["user_s"] / 2                    # half a core at T=1
    runs.to_csv(out / "runs.csv", index=False)
    done = run(out, "--no-svg")
    assert done.returncode == 0, done.stderr
    assert "the machine was busy" in (out / "report.md").read_text()


def test_one_at_a_time_T1_only_sweep_has_time_plots_only(tmp_path):
    out = copy("analysis_oat", tmp_path)
    done = run(out, "--no-svg")
    assert done.returncode == 0, done.stderr
    pngs = {p.name for p in (out / "plots").glob("*.png")}
    assert {"scaling_N.png", "scaling_L.png", "scaling_r.png"} <= pngs
    assert not any(name.startswith("speedup") for name in pngs)
    report = (out / "report.md").read_text()
    assert "single thread count" in report
    assert "| N | L=1000, r=1 | 100 to 800 | 4 | 2 | 1 |" in report


def with_runs(text):
    def setup(directory):
        (directory / "runs.csv").write_text(text)
        return directory
    return setup


@pytest.mark.parametrize("setup,message", [
    (lambda d: d / "missing", "does not exist"),
    (lambda d: d, "runs.csv not found"),
    (with_runs(""), "is empty"),
    (with_runs("engine,N,T\nbrute,1,1\n"), "status, wall_s"),
    (lambda d: Path(shutil.copytree(FIXTURES / "analysis_no_baseline", d / "nb")),
     "no successful run at T=1"),
])
def test_bad_input_exits_2_with_one_message(tmp_path, setup, message):
    done = run(setup(tmp_path))
    assert done.returncode == 2
    assert message in done.stderr
    assert "Traceback" not in done.stderr
    assert done.stderr.startswith("plots: error: ")
