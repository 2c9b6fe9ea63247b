"""The machine's ceilings (docs/performance.md, "The machine's ceilings") for sanity, on this
machine as it is now: the pair kernel's peak at least as fast per pair test as brute's own narrow
phase measured beside it, the triad's bandwidth within 0.1x to 10x of a plain memcpy's, and
psweep recording the ceilings in meta.json, measured once per machine and build and then cached
(or as make ceilings measured them last).
Ratios only: on a shared machine no absolute speed holds from one minute to the next."""
import json
import os
import shutil
import subprocess

import pytest

from build_path import BUILD, sanitized

CEILINGS = BUILD / "ceilings"
PSIM = BUILD / "psim"
PSWEEP = BUILD / "psweep"

pytestmark = pytest.mark.skipif(not CEILINGS.is_file(), reason=f"{CEILINGS} is not built")
# A sanitizer checks every access of the kernels' loops but not memcpy's: their speeds mean nothing.
speeds = pytest.mark.skipif(sanitized(), reason="a sanitizer build's speeds are its checks'")


def measure_ceilings(folder):
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / "ceilings.json"
    done = subprocess.run([str(CEILINGS), "--repetitions", "3", "--out", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "pair test, T=1 (ns)" in done.stdout  # the table
    return json.loads(out.read_text())


@pytest.fixture(scope="module")
def ceilings(tmp_path_factory):
    return measure_ceilings(tmp_path_factory.mktemp("ceilings"))


def brute_ns_per_pair_test(tmp_path, runs=3):
    """brute's narrow phase per pair test on the default scene (N = 1000, shortened), T = 1: the
    least of `runs` runs, as every time of the lab is read."""
    scene = tmp_path / "default.in"
    scene.write_text("1000\n20000\n1\n100\nperf\n")
    best = None
    for k in range(runs):
        metrics = tmp_path / f"brute-{k}.json"
        subprocess.run([str(PSIM), "--engine", "brute", "--threads", "1", "--seed", "3210",
                        "--metrics", str(metrics), str(scene)],
                       check=True, capture_output=True, timeout=60)
        run = json.loads(metrics.read_text())
        ns = run["stages"]["narrow_phase_s"] * 1e9 / run["counters"]["pair_tests"]
        best = ns if best is None else min(best, ns)
    return best


@speeds
def test_the_peak_is_at_least_as_fast_as_brute(ceilings, tmp_path):
    peak = ceilings["pair_kernel"]["T1"]["ns_per_pair_test"]
    assert peak["min"] <= peak["median"] <= peak["max"]
    # brute's rows take the same pre-test plus its flagged pairs' exact tests and its rows' ends;
    # 1.25x for the noise of a shared machine between the two measurements. Where other work
    # slowed one of them (a fresh clone's CI once measured the peak at 0.47 ns beside brute's 0.36
    # while a build ran), both are measured again, the least of each kept: a kernel that is
    # really slower than brute's rows stays slower every time.
    fastest, brute = peak["min"], brute_ns_per_pair_test(tmp_path)
    for attempt in range(2):
        if fastest <= 1.25 * brute:
            break
        again = measure_ceilings(tmp_path / f"again-{attempt}")
        fastest = min(fastest, again["pair_kernel"]["T1"]["ns_per_pair_test"]["min"])
        brute = min(brute, brute_ns_per_pair_test(tmp_path))
    assert fastest <= 1.25 * brute, (fastest, brute)


@speeds
def test_the_triad_is_within_a_factor_10_of_memcpy(ceilings):
    for t in ("T1", "Tall"):
        triad = ceilings["bandwidth"]["triad"][t]["gb_per_s"]["median"]
        memcpy = ceilings["bandwidth"]["memcpy"][t]["gb_per_s"]["median"]
        assert 0.1 <= triad / memcpy <= 10, (t, triad, memcpy)


def test_figures_and_caches_are_there(ceilings):
    assert ceilings["cpus"] == len(os.sched_getaffinity(0))
    assert ceilings["pair_kernel"]["vector_bits"] in (128, 256, 512)
    assert ceilings["pair_kernel"]["rate_ratio"]["median"] > 0
    # psim's own start beside the empty process: the build's psim is beside ceilings.
    for key in ("process_s", "omp_team_s", "omp_region_s", "psim_list_engines_s",
                "psim_one_particle_s"):
        s = ceilings["startup"][key]
        assert 0 < s["min"] <= s["median"] <= s["max"] < 1, key
    if os.path.isdir("/sys/devices/system/cpu/cpu0/cache"):
        assert any(c["level"] == 1 and c["type"] == "Data" for c in ceilings["caches"])


def test_psweep_records_them_once_per_build(tmp_path):
    config = tmp_path / "tiny.json"
    config.write_text(json.dumps({"name": "tiny", "base": {"engine": "brute", "N": 20, "L": 200,
                                  "r": 1, "S": 2, "T": 1}, "repetitions": 1, "warmup": 0}))
    # The program in a folder of its own, so the cache starts empty; one repetition per figure.
    program = tmp_path / "bin" / "ceilings"
    program.parent.mkdir()
    program.write_text(f'#!/bin/sh\nexec "{CEILINGS}" --repetitions 1 "$@"\n')
    program.chmod(0o755)
    env = {**os.environ, "PSWEEP_CEILINGS": str(program)}
    sources = []
    for k in range(2):
        out = tmp_path / f"out{k}"
        subprocess.run([str(PSWEEP), str(config), "--out", str(out), "--psim", str(PSIM)],
                       check=True, capture_output=True, env=env, timeout=120)
        meta = json.loads((out / "meta.json").read_text())
        sources.append(meta["ceilings"]["source"])
        assert meta["ceilings"]["pair_kernel"]["T1"]["ns_per_pair_test"]["min"] > 0
    assert sources == ["measured", "cached"]
    assert len(list((tmp_path / "bin" / "ceilings-cache").glob("*.json"))) == 1


def test_make_ceilings_refreshes_what_sweeps_record(tmp_path):
    """`ceilings --out` (make ceilings) writes its figures into the cache beside the program, so
    that the sweeps after it record them instead of whatever a first sweep measured."""
    program = tmp_path / "bin" / "ceilings"
    program.parent.mkdir()
    shutil.copy(CEILINGS, program)
    fresh = tmp_path / "fresh.json"
    subprocess.run([str(program), "--repetitions", "1", "--out", str(fresh)], check=True,
                   capture_output=True, timeout=120)
    config = tmp_path / "tiny.json"
    config.write_text(json.dumps({"name": "tiny", "base": {"engine": "brute", "N": 20, "L": 200,
                                  "r": 1, "S": 2, "T": 1}}))
    subprocess.run([str(PSWEEP), str(config), "--out", str(tmp_path / "out"), "--psim", str(PSIM)],
                   check=True, capture_output=True, timeout=120,
                   env={**os.environ, "PSWEEP_CEILINGS": str(program)})
    recorded = json.loads((tmp_path / "out" / "meta.json").read_text())["ceilings"]
    assert recorded["source"] == "cached"
    assert recorded["pair_kernel"] == json.loads(fresh.read_text())["pair_kernel"]
