"""Programs shaped like a parallel-computing course's submissions (tests/students/: an OpenMP
program whose runtime binds its threads with proc_bind(close) over OMP_PLACES, a pthreads program
that pins its own threads and takes T as its first argument), each a folder of C sources with a
Makefile, built by the grading (confined) and graded at T = 1 and 2 in both confinement tiers: each must be exact with
every judging point (issue 56: every OpenMP submission once scored 0, its threads refused their
binding), and threads that bind while the ones before them exit, run confined.
"""
import csv
import json
import shutil
import subprocess
import textwrap

import pytest

from build_path import BUILD
from entry_point import ROOT
from test_confinement import TIERS, bwrap_works, landlock_abi, skip_without_tier

STUDENTS = ROOT / "tests" / "students"
PLAIN = ROOT / "tests" / "reference" / "plain_allpairs.c"

pytestmark = pytest.mark.skipif(not bwrap_works(), reason="bwrap cannot make a sandbox here")


def sources(name: str, into) -> None:
    """tests/students/NAME with the model's source beside it: a folder of sources with a
    Makefile, as `into`/NAME."""
    shutil.copytree(STUDENTS / name, into / name, dirs_exist_ok=True)
    shutil.copy(PLAIN, into / name)


def students_config(folder) -> str:
    """configs/grade.json at T = 1 and 2 on three judging scenes and a small timing scene, T as
    every submission's first argument."""
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    config["judging"]["scenes"] = [s for s in config["judging"]["scenes"] if s["file"] in (
        "scenes/corner.in", "scenes/head_on.in", "tests/check/scenes/random200.in")]
    config["judging"]["T"] = [1, 2]
    config["timing"].update(scene={"N": 60, "L": 2000, "r": 1, "S": 20}, repetitions=1, warmup=0,
                            T=[1, 2], stretch=[])
    config["submission"] = {"args": ["{T}"]}
    path = folder / "grade_students.json"
    path.write_text(json.dumps(config))
    return str(path)


@pytest.fixture(scope="module", params=list(TIERS))
def graded(request, tmp_path_factory):
    skip_without_tier(request.param)
    root = tmp_path_factory.mktemp("students")
    folder = root / "submissions"
    folder.mkdir()
    for name in ("openmp_bind", "pthreads_pin"):
        sources(name, folder)
    out = root / "out"
    done = subprocess.run(
        TIERS[request.param] + [
            "/usr/bin/python3", "-m", "analysis", "grade", str(folder), "--out", str(out),
            "--config", students_config(root), "--psweep", str(BUILD / "psweep")],
        capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    with open(out / "scoreboard.csv", newline="") as f:
        board = {row["name"]: row for row in csv.DictReader(f)}
    return {"board": board, "out": out, "stderr": done.stderr}


@pytest.mark.parametrize("name", ["openmp_bind", "pthreads_pin"])
def test_a_program_that_binds_its_threads_is_exact_at_every_T(graded, name):
    row = graded["board"][name]
    assert row["verdict"] == "exact", (row, graded["stderr"][-2000:])
    result = json.loads((graded["out"] / "gradescope" / name / "results.json").read_text())
    judging = [t for t in result["tests"] if t["name"].startswith("judging")]
    assert judging and all(t["score"] == t["max_score"] for t in judging), judging
    timing = graded["out"] / "timing" / "runs.csv"
    with open(timing, newline="") as f:
        runs = [r for r in csv.DictReader(f) if r["engine"] == name]
    assert {r["T"] for r in runs if r["status"] == "ok"} == {"1", "2"}, runs


# Threads that pin themselves (argument "itself") or are started pinned by their creator
# ("started": glibc sets the new thread's affinity from the creator), 4 at a time, 500 times,
# while the threads before them exit: the keeper must find every caller among its process's
# threads (a pthreads submission's pinning once failed with ESRCH in one run of a hundred).
PINNED_WHILE_OTHERS_EXIT = r"""
#define _GNU_SOURCE
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
static cpu_set_t one;
static void* pin_itself(void* arg) {
  return (void*)(long)pthread_setaffinity_np(pthread_self(), sizeof one, &one);
}
static void* nothing(void* arg) { return NULL; }
int main(int argc, char** argv) {
  const int itself = argc > 1 && strcmp(argv[1], "itself") == 0;
  cpu_set_t start;
  sched_getaffinity(0, sizeof start, &start);
  int cpu = 0;
  while (!CPU_ISSET(cpu, &start)) ++cpu;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  if (!itself) pthread_attr_setaffinity_np(&attr, sizeof one, &one);
  for (int round = 0; round < 500; ++round) {
    pthread_t team[4];
    for (int i = 0; i < 4; ++i) {
      const int error = pthread_create(&team[i], &attr, itself ? pin_itself : nothing, NULL);
      if (error) return fprintf(stderr, "round %d: %s\n", round, strerror(error)), 3;
    }
    for (int i = 0; i < 4; ++i) {
      void* error;
      pthread_join(team[i], &error);
      if (error) return fprintf(stderr, "round %d: %s\n", round, strerror((int)(long)error)), 3;
    }
  }
  return 0;
}
"""


@pytest.mark.parametrize("tier", list(TIERS))
@pytest.mark.parametrize("how", ["itself", "started"])
def test_threads_pinned_while_the_ones_before_them_exit_are_pinned(tmp_path, tier, how):
    skip_without_tier(tier)
    (tmp_path / "pinned.c").write_text(PINNED_WHILE_OTHERS_EXIT)
    subprocess.run(["gcc", "-O2", "-pthread", "-o", str(tmp_path / "pinned"),
                    str(tmp_path / "pinned.c")], check=True)
    done = subprocess.run(TIERS[tier] + [str(BUILD / "psweep"), "confined", "--",
                                         str(tmp_path / "pinned"), how],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def grade_with(tmp_path, submission: dict, *names) -> tuple[subprocess.CompletedProcess, dict]:
    """The students' grading of `names` with the grade config's `submission` key replaced."""
    folder = tmp_path / "submissions"
    folder.mkdir(exist_ok=True)
    for name in names:
        sources(name, folder)
    config = json.loads(open(students_config(tmp_path)).read())
    config["judging"]["T"] = config["timing"]["T"] = [1]
    config["submission"] = submission
    path = tmp_path / "grade.json"
    path.write_text(json.dumps(config))
    out = tmp_path / "out"
    done = subprocess.run(["/usr/bin/python3", "-m", "analysis", "grade", str(folder), "--out",
                           str(out), "--config", str(path), "--psweep", str(BUILD / "psweep")],
                          capture_output=True, text=True, timeout=600, cwd=ROOT)
    board = {}
    if (out / "scoreboard.csv").is_file():
        with open(out / "scoreboard.csv", newline="") as f:
            board = {row["name"]: row for row in csv.DictReader(f)}
    return done, board


def test_a_program_built_for_K_4_is_judged_at_K_4(tmp_path):
    done, board = grade_with(tmp_path, {"slow_factor": 4}, "built_for_k4")
    assert done.returncode == 0, done.stderr[-3000:]
    assert board["built_for_k4"]["verdict"] == "exact", board["built_for_k4"]
    assert board["plain_allpairs"]["verdict"] == "exact", board["plain_allpairs"]  # at K = 4 too
    shutil.rmtree(tmp_path / "out")
    done, board = grade_with(tmp_path, {}, "built_for_k4")
    assert board["built_for_k4"]["verdict"] != "exact", board["built_for_k4"]


def test_a_program_that_numbers_its_sub_steps_is_judged_when_the_config_says_so(tmp_path):
    # As the 2019 authors' parallel-2 prints: every sub-step, numbered to S x K, v / K.
    done, board = grade_with(tmp_path, {"slow_factor": 4, "numbers": "sub-steps"},
                             "numbers_sub_steps")
    assert done.returncode == 0, done.stderr[-3000:]
    assert board["numbers_sub_steps"]["verdict"] == "exact", board["numbers_sub_steps"]
    assert board["plain_allpairs"]["verdict"] == "exact", board["plain_allpairs"]  # the lab's own
    shutil.rmtree(tmp_path / "out")
    done, board = grade_with(tmp_path, {"slow_factor": 4}, "numbers_sub_steps")
    assert board["numbers_sub_steps"]["verdict"] == "malformed", board["numbers_sub_steps"]


@pytest.mark.parametrize("submission, message", [
    ({"numbers": "sub-steps"}, "submission.numbers: expected \"time units\" (the 2019 format) "
                               "or, with a slow_factor above 1, \"sub-steps\""),
    ({"args": "{T}"}, "submission.args: expected a list of strings"),
    ({"args": ["{threads}"]}, "submission.args[0]: unknown placeholder {threads}"),
    ({"env": {"OMP_NUM_THREADS": "8"}}, "submission.env"),
    ({"slow_factor": 0}, "submission.slow_factor: expected the sub-steps K"),
    ({"argv": []}, "submission.argv: unknown key"),
])
def test_a_bad_submission_key_is_refused_in_its_own_words(tmp_path, submission, message):
    done, _ = grade_with(tmp_path, submission, "pthreads_pin")
    assert done.returncode == 2, done.stderr
    assert message in done.stderr, done.stderr


def test_a_build_command_and_a_failed_build_say_what_happened(tmp_path):
    folder = tmp_path / "submissions"
    sources("pthreads_pin", folder)
    (folder / "pthreads_pin" / "Makefile").unlink()  # built by the config's command instead
    broken = folder / "broken"
    broken.mkdir()
    (broken / "main.c").write_text("int main(void) { return syntax error; }\n")
    done, board = grade_with(tmp_path, {"args": ["{T}"], "build": "gcc -O2 -pthread -o sim "
                                        "main.c -lm", "program": "sim"})
    assert done.returncode == 0, done.stderr[-3000:]
    assert board["pthreads_pin"]["verdict"] == "exact", board["pthreads_pin"]
    assert board["broken"]["verdict"] == "failed"
    assert "the build (`gcc -O2" in board["broken"]["first_violation"], board["broken"]
    report = (tmp_path / "out" / "reports" / "broken.md").read_text()
    assert "## Build" in report and "error" in report, report


def test_a_build_runs_confined(tmp_path):
    folder = tmp_path / "submissions"
    sources("openmp_bind", folder)
    outside = tmp_path / "outside.txt"
    (folder / "openmp_bind" / "Makefile").write_text(
        "openmp_bind: main.c plain_allpairs.c\n"
        f"\t-echo forged > {outside}\n"
        "\t-python3 -c 'import socket; socket.create_connection((\"127.0.0.1\", 22), 2)' "
        "&& echo reached the host\n"
        "\tgcc -O2 -ffp-contract=off -fopenmp -o $@ main.c -lm\n")
    done, board = grade_with(tmp_path, {})
    assert done.returncode == 0, done.stderr[-3000:]
    assert board["openmp_bind"]["verdict"] == "exact", board["openmp_bind"]
    assert not outside.exists()
    report = (tmp_path / "out" / "reports" / "openmp_bind.md").read_text()
    assert "## Build" in report and "reached the host" not in report.replace("&& echo reached", "")
