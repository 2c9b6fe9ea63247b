"""A class graded in shards (analysis/grade/shards.py, `make grade-slurm`) without a cluster:
the split balanced by the estimate, speed points from ratios within one node's window, and a
small class graded by `make grade`'s tool and by plan, a task per shard and the merge run here:
the same verdicts, judging points and files; then a task resumed on another node after losing
its node mid-window, nothing finished run again. The cluster itself: tests/slurm/test_slurm.sh.
"""
import csv
import json
import os
import shutil
import subprocess
import sys

import pandas as pd
import pytest

from analysis.grade.gradescope import results_json
from analysis.grade.shards import split, windows
from build_path import BUILD
from entry_point import ROOT
from test_confinement import quick_config, write
from test_grade_rules import JUDGING, POINTS, per_scene, speed_tests


@pytest.mark.parametrize("shards", [2, 3, 5, 8])
def test_the_split_is_balanced_by_the_estimate(shards):
    # 41 submissions, a few of them folders of sources that build (priced more), several that
    # will not run at all (nothing): each shard within the largest entry of the mean, as LPT
    # promises, every entry once, and the same split whatever the order they came in.
    estimates = {f"s{i:02}": 30.0 + (i % 7) * 5 for i in range(35)}
    estimates.update({f"src{i}": 90.0 for i in range(3)})
    estimates.update({f"broken{i}": 0.0 for i in range(3)})
    groups = split(estimates, shards)
    assert sorted(n for g in groups for n in g) == sorted(estimates)
    loads = [sum(estimates[n] for n in g) for g in groups]
    mean = sum(loads) / shards
    assert max(loads) <= mean + max(estimates.values()), loads
    assert max(loads) - min(loads) <= max(estimates.values()), loads
    assert split(dict(reversed(list(estimates.items()))), shards) == groups
    # equal estimates (the cost model prices every program alike): counts within one
    counts = [len(g) for g in split({f"p{i}": 1.0 for i in range(40)}, shards)]
    assert max(counts) - min(counts) <= 1, counts


def test_windows_cut_a_shard_in_order():
    assert windows(list("abcdefg"), 3) == [["a", "b", "c"], ["d", "e", "f"], ["g"]]
    assert windows([], 3) == []


def window_runs(node: str, times: dict, scale: float) -> pd.DataFrame:
    """Three repetitions of each name on one node (`results` its window's folder), every time
    `scale` times the name's own, with a little noise between repetitions."""
    return pd.DataFrame([{"engine": name, "T": 1.0, "status": "ok", "node": node,
                          "results": f"out/shard-{node}/timing/w-1",
                          "process_s": s * scale * noise, "busy_tasks": 0}
                         for name, s in times.items() for noise in (1.0, 1.03, 1.08)])


def test_speed_points_come_from_the_ratio_on_the_submissions_own_node():
    # The same two programs graded on a node and on one twice as slow: raw times differ by 2x,
    # the points agree within the spread the speed test states (the repetitions'). Scored
    # against the fast node's reference, the slow node's copy would lose a quarter of them.
    times = {"plain_allpairs": 1.2, "quick": 0.5}
    runs = pd.concat([window_runs("n1", times, 1.0),
                      window_runs("n2", {**times, "quick_copy": times["quick"]}, 2.0)
                      .query("engine != 'quick'")])
    scenes = pd.concat([per_scene({"quick": ("exact", "exact")}, {"quick": 0.5}),
                        per_scene({"quick_copy": ("exact", "exact")}, {"quick_copy": 1.0})])
    one = speed_tests(results_json("quick", scenes, JUDGING, runs, ["plain_allpairs"], POINTS))
    two = speed_tests(results_json("quick_copy", scenes, JUDGING, runs, ["plain_allpairs"],
                                   POINTS))
    assert one[0]["score"] == pytest.approx(two[0]["score"]) and 15 < one[0]["score"] < 30
    assert "0.5 s against plain_allpairs's 1.2 s" in one[0]["output"]
    assert "1 s against plain_allpairs's 2.4 s" in two[0]["output"]
    assert "within the repetitions' spread" in one[0]["output"]
    # one window for both (make grade's one timing sweep, pooled): the slow node's copy is
    # compared with the fast node's reference
    pooled = runs.drop(columns="results")
    unfair = speed_tests(results_json("quick_copy", scenes, JUDGING, pooled, ["plain_allpairs"],
                                      POINTS))
    assert one[0]["score"] - unfair[0]["score"] > 0.2 * 30, (one, unfair)


# ------------------------------------------------------------------- a small class, both ways

def analysis(*args, env=None, timeout=600):
    return subprocess.run([sys.executable, "-m", "analysis", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, cwd=ROOT,
                          env={**os.environ, **(env or {})})


def board_of(out):
    with open(out / "scoreboard.csv", newline="") as f:
        return {row["name"]: row for row in csv.DictReader(f)}


def grades_of(out):
    with open(out / "grades.csv", newline="") as f:
        return {row["name"]: row for row in csv.DictReader(f)}


@pytest.fixture(scope="module")
def graded_both_ways(tmp_path_factory):
    root = tmp_path_factory.mktemp("shards")
    folder = root / "class"
    folder.mkdir()
    for name in ("alice", "bob", "carol"):
        shutil.copy(BUILD / "plain_allpairs", folder / name)
    for name in ("dave", "erin"):  # byte-identical wrong copies
        shutil.copy(BUILD / "check_programs" / "wall_tolerance", folder / name)
    write(folder, "frank", "#!/bin/sh\nkill -SEGV $$\n")
    write(folder, "grace", "#!/bin/sh\n", mode=0o644)  # not executable
    config = quick_config(root, seed=7)
    settings = json.loads(config.read_text())
    settings["judging"]["seed"] = 11  # both gradings judge the same drawn scenes
    config.write_text(json.dumps(settings))
    psweep = BUILD / "psweep"
    one = root / "one"
    done = analysis("grade", folder, "--out", one, "--config", config, "--psweep", psweep)
    assert done.returncode == 0, done.stderr[-3000:]
    sharded = root / "sharded"
    plan = analysis("grade-slurm", "plan", folder, "--out", sharded, "--shards", 2,
                    "--window", 2, "--config", config, "--psweep", psweep)
    assert plan.returncode == 0, plan.stderr[-3000:]
    tasks = [analysis("grade-slurm", "task", sharded, i, env={"SLURMD_NODENAME": f"node{i}"})
             for i in (1, 2)]
    for task in tasks:
        assert task.returncode == 0, task.stderr[-3000:]
    merged = analysis("grade-slurm", "merge", sharded)
    assert merged.returncode == 0, merged.stderr[-3000:]
    return root, one, sharded, plan, tasks


def test_the_plan_splits_the_class_and_says_its_node_hours(graded_both_ways):
    _, _, sharded, plan, _ = graded_both_ways
    saved = json.loads((sharded / "grade-slurm.json").read_text())
    assert sorted(n for g in saved["shards"] for n in g) == \
        ["alice", "bob", "carol", "dave", "erin", "frank", "grace"]
    assert [len(g) for g in saved["shards"]] in ([4, 3], [3, 4])
    assert "7 submissions of" in plan.stderr and "node-hours in all" in plan.stderr
    assert saved["node_hours"] > 0 and saved["cpus"] == 1


def test_the_merge_writes_what_one_machine_writes(graded_both_ways):
    _, one, sharded, _, _ = graded_both_ways
    a, b = board_of(one), board_of(sharded)
    assert set(a) == set(b)
    columns = ["kind", "verdict", "verdict_T1", "scene", "first_violation", "corner", "head_on",
               "timing"]
    for name in a:
        assert [a[name][c] for c in columns] == [b[name][c] for c in columns], name
    ga, gb = grades_of(one), grades_of(sharded)
    assert set(ga) == set(gb) == {"alice", "bob", "carol", "dave", "erin", "frank", "grace"}
    for name in ga:
        assert ga[name]["judging_score"] == gb[name]["judging_score"], name
        assert ga[name]["max_score"] == gb[name]["max_score"], name
    for out in (one, sharded):
        assert sorted(p.name for p in (out / "gradescope").iterdir()) == sorted(ga)
        assert sorted(p.name for p in (out / "reports").glob("*.md")) == \
            sorted(f"{n}.md" for n in ga)
        assert (out / "class.html").is_file() and (out / "scoreboard.html").is_file()
    # the class report of the merged class counts what its grades.csv says
    page = (sharded / "class.md").read_text()
    assert "7 submissions: median" in page
    assert "- dave, erin" in page.split("## Byte-identical outputs")[1]
    # each submission timed beside the reference on its own node, and the board keeps both
    for name in ("alice", "bob", "carol"):
        row = b[name]
        assert row["node"] in ("node1", "node2") and float(row["reference_s"]) > 0, row
        assert float(row["time_T1_s"]) > 0
    assert a["alice"]["node"] and float(a["alice"]["reference_s"]) > 0
    nodes = {r["name"]: r for r in csv.DictReader(open(sharded / "nodes.csv"))}
    assert set(nodes) == set(ga)
    assert nodes["alice"]["timed_on"] == b["alice"]["node"]
    assert nodes["frank"]["timed_on"] == "" and nodes["frank"]["judged_on"] in ("node1", "node2")


def test_progress_covers_the_whole_class(graded_both_ways):
    _, _, sharded, _, tasks = graded_both_ways
    done = analysis("grade-slurm", "progress", sharded)
    assert done.returncode == 0 and done.stdout.startswith("grade-slurm: 7 of 7 submissions "
                                                           "graded"), done.stdout
    assert any("of the class's 7): [1/3] judging" in t.stderr for t in tasks), tasks[0].stderr


def test_a_task_requeued_on_another_node_loses_no_finished_grade(graded_both_ways):
    root, _, _, _, _ = graded_both_ways
    again = root / "again"
    plan = analysis("grade-slurm", "plan", root / "class", "--out", again, "--shards", 1,
                    "--window", 2, "--config", root / "grade_quick.json", "--psweep",
                    BUILD / "psweep")
    assert plan.returncode == 0, plan.stderr[-3000:]
    task = analysis("grade-slurm", "task", again, 1, env={"SLURMD_NODENAME": "node1"})
    assert task.returncode == 0, task.stderr[-3000:]
    shard = again / "shard-1"
    timed_windows = sorted((shard / "timing").glob("w-*"))
    assert len(timed_windows) == 3, timed_windows  # alice, bob, carol, dave, erin: 2 + 2 + 1
    judged = {p: p.read_bytes() for p in (shard / "judge").glob("*/runs.csv")}
    first = (timed_windows[0] / "runs.csv").read_bytes()
    # The node lost in the middle of the last window: its marker never written, half its rows.
    last = timed_windows[-1]
    (shard / "done").unlink()
    (last / "done").unlink()
    rows = (last / "runs.csv").read_text().splitlines(keepends=True)
    (last / "runs.csv").write_text("".join(rows[:1 + (len(rows) - 1) // 2]))
    refused = analysis("grade-slurm", "merge", again)
    assert refused.returncode == 2 and "shard-1 is not finished" in refused.stderr
    task = analysis("grade-slurm", "task", again, 1, env={"SLURMD_NODENAME": "node9"})
    assert task.returncode == 0, task.stderr[-3000:]
    # nothing finished ran again: the judging rows and the first window as they were
    assert {p: p.read_bytes() for p in judged} == judged
    assert (timed_windows[0] / "runs.csv").read_bytes() == first
    assert "timing window 1/3: done before" in task.stderr
    # the cut window set aside, timed again from its start on the new node
    assert (last.parent / f"{last.name}.lost-1").is_dir()
    assert set(pd.read_csv(last / "runs.csv")["node"]) == {"node9"}
    merged = analysis("grade-slurm", "merge", again)
    assert merged.returncode == 0, merged.stderr[-3000:]
    board = board_of(again)
    assert {n for n, r in board.items() if r["node"] == "node9"} == {"erin"}, board
    assert {n for n, r in board.items() if r["node"] == "node1"} == {"alice", "bob", "carol",
                                                                     "dave"}
    nodes = {r["name"]: r for r in csv.DictReader(open(again / "nodes.csv"))}
    assert nodes["erin"]["judged_on"] == "node1" and nodes["erin"]["timed_on"] == "node9"


# ---------------------------------------------------------------------------------- the scale

PEAK = """import resource, subprocess, sys
# The soft limit: the sandbox sets a submission's own limits, up to the hard one.
resource.setrlimit(resource.RLIMIT_NOFILE,
                   (int(sys.argv[1]), resource.getrlimit(resource.RLIMIT_NOFILE)[1]))
done = subprocess.run(sys.argv[2:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
print(done.stderr[-2000:], file=sys.stderr)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
sys.exit(done.returncode)
"""
# Open files allowed each process of the grading, 2 submissions or 200 alike: a grading that
# held one per submission (a report, an output, a run's pipe left open) would run out.
FILES = 64


def peak_rss_kib(folder, out, config):
    """make grade's tool on FOLDER with at most FILES open files per process; the largest
    resident memory any of its processes reached (psweep, psim check, the grader)."""
    done = subprocess.run([sys.executable, "-c", PEAK, str(FILES), sys.executable, "-m",
                           "analysis", "grade", str(folder), "--out", str(out), "--config",
                           str(config), "--psweep", str(BUILD / "psweep")],
                          capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return int(done.stdout.split()[-1])


def test_a_class_of_200_needs_no_more_memory_or_files_than_2(tmp_path):
    config = quick_config(tmp_path)
    settings = json.loads(config.read_text())
    settings["judging"]["scenes"] = settings["judging"]["scenes"][:1]
    settings["timing"].update(repetitions=1, warmup=0)
    config.write_text(json.dumps(settings))
    peaks = {}
    for count in (2, 200):
        folder = tmp_path / f"class{count}"
        folder.mkdir()
        for i in range(count):  # each run a few milliseconds: prints nothing, is malformed
            write(folder, f"s{i:03}", "#!/bin/sh\nexec cat >/dev/null\n")
        peaks[count] = peak_rss_kib(folder, tmp_path / f"out{count}", config)
        assert len(grades_of(tmp_path / f"out{count}")) == count
    # The runs table grows by a few rows a submission, nothing beside the interpreter's and
    # pandas' own 100 MB.
    assert peaks[200] <= 1.15 * peaks[2], peaks
