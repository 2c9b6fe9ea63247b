"""make gradescope (scripts/gradescope/): the autograder zip holds the lab with setup.sh and
run_autograder at its root, and run_autograder grades one submission confined where the
container refuses namespaces (build/without_namespaces emulates it), handing over results.json.
"""
import json
import os
import re
import shutil
import subprocess
import zipfile

from build_path import BUILD
from entry_point import ROOT
from test_confinement import CACHER, compile_c, landlock_abi, quick_config

import pytest


def test_the_zip_holds_the_lab_and_its_two_entry_points(tmp_path):
    out = tmp_path / "autograder.zip"
    subprocess.run(["/usr/bin/python3", "scripts/gradescope/zip.py", str(out)], cwd=ROOT,
                   check=True, capture_output=True)
    with zipfile.ZipFile(out) as z:
        names = set(z.namelist())
        assert {"setup.sh", "run_autograder", "Makefile", "configs/grade.json",
                "scripts/bootstrap.sh"} <= names
        for entry in ("setup.sh", "run_autograder"):
            assert z.getinfo(entry).external_attr >> 16 == 0o100755


@pytest.mark.skipif(landlock_abi() < 1, reason="no Landlock: the container tier cannot work here")
def test_run_autograder_grades_one_submission_confined_without_namespaces(tmp_path):
    autograder = tmp_path / "autograder"
    (autograder / "submission").mkdir(parents=True)
    (autograder / "source").symlink_to(ROOT)
    shutil.copy(BUILD / "plain_allpairs", autograder / "submission" / "sim")
    env = dict(os.environ, AUTOGRADER=str(autograder), GRADE_CONFIG=str(quick_config(tmp_path)))
    done = subprocess.run([str(BUILD / "without_namespaces"),
                           str(ROOT / "scripts" / "gradescope" / "run_autograder")],
                          capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    assert "programs run confined by landlock+seccomp" in done.stderr
    result = json.loads((autograder / "results" / "results.json").read_text())
    judging = [t for t in result["tests"] if t["name"].startswith("judging: ")]
    assert judging and all(t["status"] == "passed" for t in judging)
    assert result["score"] > 70


def test_two_files_are_refused_with_a_sentence_for_the_student(tmp_path):
    autograder = tmp_path / "autograder"
    (autograder / "submission").mkdir(parents=True)
    (autograder / "source").symlink_to(ROOT)
    for name in ("a", "b"):
        (autograder / "submission" / name).write_text("#!/bin/sh\n")
    done = subprocess.run([str(ROOT / "scripts" / "gradescope" / "run_autograder")],
                          capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, AUTOGRADER=str(autograder)))
    assert done.returncode == 0, done.stderr
    result = json.loads((autograder / "results" / "results.json").read_text())
    assert result["score"] == 0 and "expected one program" in result["output"]


@pytest.mark.skipif(landlock_abi() < 1, reason="no Landlock: the container tier cannot work here")
def test_run_autograder_builds_a_folder_of_sources_with_a_makefile(tmp_path):
    autograder = tmp_path / "autograder"
    shutil.copytree(ROOT / "tests" / "students" / "openmp_bind", autograder / "submission")
    shutil.copy(ROOT / "tests" / "reference" / "plain_allpairs.c", autograder / "submission")
    (autograder / "source").symlink_to(ROOT)
    env = dict(os.environ, AUTOGRADER=str(autograder), GRADE_CONFIG=str(quick_config(tmp_path)))
    done = subprocess.run([str(BUILD / "without_namespaces"),
                           str(ROOT / "scripts" / "gradescope" / "run_autograder")],
                          capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    assert "grade: building sources (`make`)" in done.stderr, done.stderr
    result = json.loads((autograder / "results" / "results.json").read_text())
    judging = [t for t in result["tests"] if t["name"].startswith("judging: ")]
    assert judging and all(t["status"] == "passed" for t in judging), judging


@pytest.mark.skipif(landlock_abi() < 1, reason="no Landlock: the container tier cannot work here")
def test_answers_cached_in_sysv_memory_earn_nothing_through_the_zip(tmp_path):
    # Its cache once worked here: score 100, "15.8x" the reference's speed (issue 57).
    autograder = tmp_path / "autograder"
    (autograder / "submission").mkdir(parents=True)
    (autograder / "source").symlink_to(ROOT)
    compile_c(autograder / "submission" / "cacher", CACHER)
    # A timing scene long enough (about 0.1 s) for a cached answer (a few ms) to show.
    config = quick_config(tmp_path, N=1000, S=60)
    env = dict(os.environ, AUTOGRADER=str(autograder), GRADE_CONFIG=str(config))
    done = subprocess.run([str(BUILD / "without_namespaces"),
                           str(ROOT / "scripts" / "gradescope" / "run_autograder")],
                          capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    result = json.loads((autograder / "results" / "results.json").read_text())
    speed = [t for t in result["tests"] if t["name"].startswith("speed: ")]
    assert speed, result["tests"]
    for test in speed:
        ratio = float(re.search(r": ([0-9.e+]+)x its speed", test["output"]).group(1))
        assert ratio < 3, test["output"]
