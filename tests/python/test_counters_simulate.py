"""Counters everywhere (docs/sweeps.md, `counters`): where perf_event offers no hardware events,
psweep says so once; `counters: "simulate"` runs each configuration once more under cachegrind
(make regress's scripts/psim-cachegrind) and fills instructions, cache_misses and branch_misses,
with counters_source saying where they came from. Instructions within 2% of make regress's own
count of the same configuration; a build valgrind cannot run is refused before anything runs."""
import csv
import json
import shutil
import subprocess

import pytest

from build_path import BUILD, countable_build, sanitized
from analysis.regress.suite import cpu_isa_flags, measure, parse_suite, uses_avx512

BASE = {"engine": "brute", "N": 300, "L": 5000, "r": 1, "S": 20, "T": 1}
ENGINES = ["brute", "sweep"]


def sweep(psweep, tmp_path, name, *args, **config):
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps({"name": name, "base": BASE, "sweep": {"engine": ENGINES},
                                "repetitions": 2, **config}))
    done = subprocess.run([str(psweep), str(path), "--out", str(tmp_path / name), *args],
                          capture_output=True, text=True, timeout=300)
    rows = (list(csv.DictReader(open(tmp_path / name / "runs.csv")))
            if (tmp_path / name / "runs.csv").exists() else [])
    return done, rows


def test_without_simulation_the_source_says_what_counted(tmp_path):
    done, rows = sweep(BUILD / "psweep", tmp_path, "plain")
    assert done.returncode == 0, done.stderr
    meta = json.loads((tmp_path / "plain" / "meta.json").read_text())
    for row in rows:  # hardware where perf counted them, empty where nothing did
        assert row["counters_source"] == ("hardware" if row["instructions"] else "")
        assert row["simulated_instructions"] == row["simulated_cache_misses"] == ""
    if not meta["counters"]["hardware"]:
        assert done.stderr.count("no hardware perf events here") == 1
        assert all(row["counters_source"] == "" for row in rows)


@pytest.mark.skipif(not (uses_avx512(BUILD) and "avx512f" in cpu_isa_flags()),
                    reason="this build has no AVX-512 for valgrind to choke on")
def test_a_build_with_avx512_is_refused(tmp_path):
    done, rows = sweep(BUILD / "psweep", tmp_path, "refused", "--counters", "simulate")
    assert done.returncode == 2 and rows == []
    assert 'counters: "simulate"' in done.stderr and "AVX-512" in done.stderr
    assert "build-regress" in done.stderr


@pytest.mark.skipif(not (countable_build() / "psweep").exists(),
                    reason="needs a build valgrind can run: make build, or on an AVX-512 CPU "
                           "make regress (build-regress)")
@pytest.mark.skipif(sanitized(), reason="valgrind cannot run a sanitizer build")
def test_simulated_counters_match_make_regress(tmp_path):
    assert shutil.which("valgrind"), "valgrind is missing: scripts/bootstrap.sh installs it"
    done, rows = sweep(countable_build() / "psweep", tmp_path, "simulated", counters="simulate")
    assert done.returncode == 0, done.stderr
    assert len(rows) == 4 and {row["counters_source"] for row in rows} == {"simulated"}
    for row in rows:
        assert int(row["cache_misses"]) > 0 and int(row["branch_misses"]) > 0
        assert int(row["cache_misses"]) < int(row["instructions"])
        # the simulated counts beside the columns they fill: a machine that counts in hardware
        # keeps its own there, and the two compare row by row
        assert (row["simulated_instructions"], row["simulated_cache_misses"],
                row["simulated_branch_misses"]) == (row["instructions"], row["cache_misses"],
                                                    row["branch_misses"])
    meta = json.loads((tmp_path / "simulated" / "meta.json").read_text())
    assert meta["counters"]["simulated"].startswith("--cache-sim=yes --branch-sim=yes")

    suite = parse_suite(json.dumps({"groups": [{"name": "simulated", "base": BASE,
                                                "sweep": {"engine": ENGINES}}]}), "tiny.json")
    regress, _ = measure(suite, countable_build(), tmp_path / "regress", ("instructions",))
    counted = regress.set_index("engine")["value"]
    for engine in ENGINES:
        simulated = {int(row["instructions"]) for row in rows if row["engine"] == engine}
        assert len(simulated) == 1  # one simulated run per configuration, in every row
        assert simulated.pop() == pytest.approx(counted[engine], rel=0.02), engine
