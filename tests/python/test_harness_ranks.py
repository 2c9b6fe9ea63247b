"""psweep sweeps ranks as it sweeps threads (issue 43 item 4), end to end with the real psim and
the default launcher (mpirun): P multiplies only the mpi engine's runs, each launched on P ranks
and ending in brute's state hash, with the ranks' traffic in runs.csv; --dry-run --count's
estimate follows P; a bad P or launcher is exit 2 naming the key. Skipped, with psim's reason,
in a build without MPI.
"""
import csv
import json
import subprocess

import pytest

from build_path import BUILD
from test_harness_psweep import PSIM, PSWEEP, ROOT, read_csv

RANK_COLUMNS = ["ranks", "nodes", "halo_particles_max", "halo_particles_mean", "bytes_sent_max",
                "bytes_sent_mean", "filter_rounds", "comm_s_max", "comm_s_mean", "wait_s_max",
                "wait_s_mean"]


def mpi_unavailable() -> str:
    if not PSIM.is_file():
        return f"{PSIM} is missing"
    described = json.loads(subprocess.run([str(PSIM), "--describe"], capture_output=True,
                                          text=True, check=True).stdout)
    return next((e.get("unavailable", "") for e in described["engines"] if e["name"] == "mpi"),
                "psim declares no mpi engine")


pytestmark = pytest.mark.skipif(bool(mpi_unavailable()), reason=mpi_unavailable() or "ok")


def write(tmp_path, config, name="ranks"):
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(config))
    return path


def psweep(*args, timeout=120, wrapper=()):
    """psweep ARGS, under `wrapper`'s words (e.g. build/without_namespaces) where given."""
    return subprocess.run([*wrapper, str(PSWEEP), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=ROOT)


TINY = {"name": "ranks",
        # slow enough that particles stay near their slab and the halo is a part, not all
        "base": {"engine": "mpi", "N": 200, "L": 2000, "r": 1, "S": 30, "seed": 5, "T": 1,
                 "speed_min": 1, "speed_max": 40},
        "sweep": {"engine": ["brute", "mpi"], "P": [1, 2]},
        "repetitions": 1, "pin": "close", "timeout_s": 60}


def test_a_sweep_over_p_runs_the_mpi_engine_on_p_ranks_with_brutes_bits(tmp_path):
    out = tmp_path / "out"
    done = psweep(write(tmp_path, TINY), "--out", out)
    assert done.returncode == 0, done.stderr
    header, runs = read_csv(out / "runs.csv")
    assert header.index("P") == header.index("T") + 1
    for column in RANK_COLUMNS:
        assert column in header
    assert sorted((r["engine"], r["P"]) for r in runs) == [("brute", ""), ("mpi", "1"),
                                                            ("mpi", "2")]
    assert {r["status"] for r in runs} == {"ok"}, [r["error"] for r in runs]
    brute = next(r for r in runs if r["engine"] == "brute")
    assert all(r[c] == "" for c in RANK_COLUMNS for r in [brute])  # one process: no ranks
    for r in runs:
        assert r["state_hash"] == brute["state_hash"], r
        if r["engine"] == "mpi":
            assert int(r["ranks"]) == int(r["P"])  # the launcher started P ranks
            assert r["nodes"] == "1"  # all on this machine (make test-slurm: across nodes)
            assert all(r[c] != "" for c in RANK_COLUMNS)
    two = next(r for r in runs if r["P"] == "2")
    assert 0 < float(two["halo_particles_mean"]) < 200 * 30
    assert float(two["bytes_sent_max"]) >= float(two["bytes_sent_mean"]) > 0
    assert float(two["comm_s_max"]) >= float(two["wait_s_max"]) >= 0
    one = next(r for r in runs if r["P"] == "1")
    assert one["halo_particles_max"] == "0" and one["bytes_sent_max"] == "0"
    # Rounds filter the contested candidates alone; a candidate between two ranks always is one,
    # and the others are the same at any P: P = 2 needs the rounds of P = 1 at least.
    assert int(two["filter_rounds"]) >= int(one["filter_rounds"]) >= 0
    _, summary = read_csv(out / "summary.csv")
    assert sorted(r["P"] for r in summary) == ["", "1", "2"]
    meta = json.loads((out / "meta.json").read_text())
    assert meta["launcher"][0] == "mpirun" and "{P}" in meta["launcher"]


def test_dry_run_counts_and_estimates_follow_p(tmp_path):
    def estimate(ps):
        config = dict(TINY, sweep={"P": ps}, base=dict(TINY["base"], N=20000, S=2000))
        done = psweep(write(tmp_path, config), "--dry-run", "--count")
        assert done.returncode == 0, done.stderr
        line = next(l for l in done.stdout.splitlines() if l.startswith("mpi "))
        return done.stdout, line.split()

    text, one = estimate([1])
    assert "largest P: 1" in text
    text, three = estimate([1, 2, 4])
    assert three[1] == "3" and "largest P: 4" in text  # P multiplies the mpi engine's runs
    listed = psweep(write(tmp_path, dict(TINY, sweep={"engine": ["brute", "mpi"],
                                                      "P": [1, 2, 4]})), "--dry-run")
    assert listed.returncode == 0, listed.stderr
    lines = [l for l in listed.stdout.splitlines() if "engine=" in l]
    assert len(lines) == 1 + 3  # brute once, whatever P
    assert sum(" P=" in l for l in lines) == 3


def test_the_estimate_of_a_run_falls_with_p_on_two_cpus(tmp_path):
    # 20000 particles x 2000 sub-steps at 330 ns: 13 s at P = 1, about half at P = 2
    def seconds(p):
        config = dict(TINY, sweep={"P": [p]}, base=dict(TINY["base"], N=20000, S=2000))
        out = psweep(write(tmp_path, config), "--dry-run", "--count").stdout
        estimate = next(l for l in out.splitlines() if l.startswith("mpi ")).split()[3:]
        value, unit = float(estimate[0]), estimate[1]
        return value * {"s": 1, "min": 60, "h": 3600}[unit]

    assert 1.6 < seconds(1) / seconds(2) < 2.1


@pytest.mark.parametrize("extra, message", [
    ({"sweep": {"P": [2, 0]}}, "ranks.json: sweep.P[1]: expected a positive integer, got 0"),
    ({"sweep": {"P": [9999]}}, "ranks.json: sweep.P[0]: expected at most 4096 ranks, got 9999"),
    ({"launcher": ["mpirun", "-n", "4"]}, "ranks.json: launcher: names no {P}"),
    ({"launcher": "srun -n {P}"}, "ranks.json: launcher: expected a non-empty list of strings"),
    ({"launcher": ["no-such-launcher-here", "-n", "{P}"]},
     'ranks.json: launcher[0]: cannot execute "no-such-launcher-here": not found on PATH'),
])
def test_bad_p_or_launcher_is_exit_2_naming_the_key(tmp_path, extra, message):
    done = psweep(write(tmp_path, dict(TINY, **extra)), "--dry-run")
    assert done.returncode == 2
    assert message in done.stderr, done.stderr
