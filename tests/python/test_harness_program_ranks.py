"""An external program of P ranks (docs/programs.md, "Programs of ranks"): a program that lists "P"
in `uses` starts its ranks itself, with its own mpirun and {P} in its command, inside its
confinement, and is timed and judged per P as any program. The program here is the lab's own mpi
engine run through a program entry, so that what is judged is a real MPI program's output: psim-mpi,
which has the engine itself (the sandbox holds the files a command names, and psim alone would
find no psim-mpi beside it)."""
import csv
import json

import pytest

from build_path import BUILD
from test_confinement import bwrap_works, landlock_abi
from test_harness_ranks import mpi_unavailable, psweep, write

pytestmark = pytest.mark.skipif(bool(mpi_unavailable()), reason=mpi_unavailable() or "ok")


def config(*mpirun_options):
    return {"name": "program-ranks",
            "base": {"engine": "psim_mpi", "N": 60, "L": 600, "r": 1, "S": 12, "seed": 5, "T": 1},
            "sweep": {"P": [1, 2]},
            "repetitions": 1, "timeout_s": 60,
            "programs": {"psim_mpi": {
                "command": ["mpirun", *mpirun_options, "-np", "{P}", str(BUILD / "psim-mpi"),
                            "--engine", "mpi", "{scene}"],
                "input": "file", "uses": ["P"], "growth": "N"}}}


def runs_of(out):
    with open(out / "runs.csv", newline="") as f:
        return sorted(csv.DictReader(f), key=lambda r: r["P"])


@pytest.mark.skipif(not bwrap_works(), reason="bwrap cannot make a sandbox here")
def test_a_program_of_ranks_is_judged_exact_at_each_p_inside_bwrap(tmp_path):
    out = tmp_path / "out"
    # uid 0 of the sandbox's user namespace (nobody outside): OpenMPI wants to be told.
    done = psweep(write(tmp_path, config("--allow-run-as-root")), "--out", out)
    assert done.returncode == 0, done.stderr
    runs = runs_of(out)
    assert [r["P"] for r in runs] == ["1", "2"]
    for r in runs:
        assert (r["status"], r["check"]) == ("ok", "exact"), (r["error"], r["check_detail"])
    meta = json.loads((out / "meta.json").read_text())
    assert meta["confinement"]["tool"] == "bwrap"
    assert meta["programs"]["psim_mpi"]["uses"] == ["P"]


@pytest.mark.skipif(not bwrap_works(), reason="bwrap cannot make a sandbox here")
def test_mpirun_refuses_the_sandboxs_root_without_being_told_and_the_row_says_so(tmp_path):
    out = tmp_path / "out"
    done = psweep(write(tmp_path, config()), "--out", out)
    assert done.returncode == 0, done.stderr
    for r in runs_of(out):
        assert r["status"] == "failed" and "OMPI_ALLOW_RUN_AS_ROOT" in r["error"], r["error"]


@pytest.mark.skipif(landlock_abi() < 1, reason="the kernel offers no Landlock")
def test_the_second_tier_refuses_the_tcp_openmpi_needs_a_failed_row_at_once(tmp_path):
    # Without namespaces (build/without_namespaces, as a container's seccomp profile), the tier
    # refuses every socket but AF_UNIX; OpenMPI 4.1's PMIx server listens on TCP even on one
    # machine (its "usock" transport is gone), so mpirun stops at once, never hangs.
    out = tmp_path / "out"
    done = psweep(write(tmp_path, config("--allow-run-as-root")), "--out", out,
                  wrapper=[str(BUILD / "without_namespaces")], timeout=30)
    assert done.returncode == 0, done.stderr
    assert json.loads((out / "meta.json").read_text())["confinement"]["tool"] == "landlock+seccomp"
    for r in runs_of(out):
        assert r["status"] == "failed" and "PMIx server's listener" in r["error"], r["error"]
        assert float(r["process_s"]) < 10
