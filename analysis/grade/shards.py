"""A class graded over a cluster's nodes (`make grade-slurm PROGRAMS=DIR SHARDS=n`,
docs/programs.md, "A class on a Slurm cluster"): the same grading as `make grade` (cli.py), cut
into shards that run apart and a merge that writes the one OUT `make grade` writes.

  plan   DIR --out OUT --shards n   draws the judging scenes and the seeds once for the class
                                    (OUT/drawn/), refuses a bad config before anything is
                                    submitted (exit 2, in the config's words), splits the
                                    submissions into n groups balanced by the grading's
                                    estimate, and writes OUT/grade-slurm.json; --dry-run says
                                    the split and the node-hours and writes nothing
  task   OUT I                      shard I (an array task): builds, judges and times its group
                                    into OUT/shard-I on the node it runs on
  merge  OUT                        (the dependent job) every shard's sweeps scored as one
                                    class into OUT, and OUT/nodes.csv: which node graded whom
  progress OUT                      the whole class's progress, from the shards' folders

Speed points are fair across unequal nodes because no time is compared across nodes: a shard
times its submissions in windows of a few (`--window`), each window one psweep of the window's
submissions and the references (timing.engines and timing.stretch), interleaved repetition by
repetition on the node, and a submission's speed is its time over the reference's in its own
window (gradescope.window). A window is a grade's unit of resumption: once its sweep ended it is
marked done and never rerun; a task requeued after its node was lost resumes its judging sweeps
(psweep --resume: each run once) and redoes only the window that was under way, from the start on
its new node when the rows it has are another node's (moved aside, not mixed: a window's times
are one node's). Memory and open files do not grow with the class: a task holds its group, a
window at a time; the merge holds the class's runs table (a few thousand rows a submission) and
writes one report at a time.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import pandas as pd

from analysis.common.csv_out import write_csv
from analysis.common.load import InputError, load_results
from analysis.grade.build import buildable
from analysis.grade.cli import (Setup, build_sources, check_configs, exit_status, judge,
                                say_drawn, say_timing_seed, score, setup, to_time, write_meta)
from analysis.grade.draw import draw_scenes, drawn_in
from analysis.grade.plan import Submission, duration, timing_config

PLAN = "grade-slurm.json"
DONE = "done"      # a timing window's marker: its sweep ended, its grades are final
WINDOW = 8         # submissions per timing window by default


def split(estimates: dict[str, float], shards: int) -> list[list[str]]:
    """The entries (name -> estimated seconds) in `shards` groups of about equal estimate:
    largest first, each to the group with the least so far (LPT, as psweep's --shard splits a
    sweep), ties by name, so that every caller gets the same split. Each group in name order."""
    groups: list[list[str]] = [[] for _ in range(shards)]
    load = [0.0] * shards
    for name in sorted(estimates, key=lambda n: (-estimates[n], n)):
        k = min(range(shards), key=lambda i: (load[i], i))
        groups[k].append(name)
        load[k] += estimates[name]
    return [sorted(g) for g in groups]


def windows(names: list[str], size: int) -> list[list[str]]:
    """A shard's timed submissions in windows of `size`, in order."""
    return [names[i:i + size] for i in range(0, len(names), size)]


def node_name() -> str:
    """This node as psweep names it in runs.csv's `node`: Slurm's name in a job, else the host."""
    return os.environ.get("SLURMD_NODENAME") or socket.gethostname()


def read_plan(out: Path) -> dict:
    path = out / PLAN
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"{path} not found: plan the class first (make grade-slurm, or "
                         f"grade-slurm plan DIR --out {out} --shards N)") from None
    except json.JSONDecodeError as err:
        raise InputError(f"{path}: not JSON ({err})") from None


def class_setup(plan: dict, out: Path, only: set[str] | None = None) -> Setup:
    """The grading as the plan fixed it: its seeds, and its judging scenes as drawn into OUT."""
    s = setup(plan["submissions"], plan["config"], plan["psweep"], plan["unconfined"],
              (tuple(plan["timing_seed"]), tuple(plan["judging_seed"])), only)
    s.config = replace(s.config, scenes=drawn_in(s.config.scenes, out))
    return s


# ---------------------------------------------------------------------------------------- plan

def estimates_s(s: Setup, out: Path) -> tuple[dict[str, float], float]:
    """The grading's estimate (psweep's cost model, as make grade states it) per entry, and a
    timing window's references: each submission as the cost model prices it, a program with
    its judging and timing runs (the same for every program, the model pricing each as a plain
    all-pairs one); an entry that will not run, nothing."""
    runnable = [e for e in s.entries if e.path is not None]
    probe = {e.program: e.path for e in runnable[:1]}
    references = s.sweep.check(timing_config(s.config, {}, s.timing_seed[0], s.lab),
                               out / "configs" / "timing-references.json", {})
    each = 0.0
    if probe:
        each = check_configs(s.sweep, s.config, probe, s.shown, s.timing_seed[0], s.lab,
                             out) - references
    elif any(e.source is not None for e in s.entries):
        # Only folders of sources: priced as a program, the references' own program standing in.
        stand_in = {"program": next(iter(s.lab.values()), Path(s.psweep).parent / "psim")}
        each = check_configs(s.sweep, s.config, stand_in, {"program": "program"},
                             s.timing_seed[0], s.lab, out) - references
    return ({e.name: each if e.path is not None or (e.source is not None and buildable(
        e.source, s.config.submission)) else 0.0 for e in s.entries}, references)


def shard_estimate(group: list[str], estimates: dict[str, float], references: float,
                   size: int) -> float:
    """A shard's seconds: its submissions, and the references once per timing window."""
    timed = [n for n in group if estimates[n] > 0]
    return sum(estimates[n] for n in group) + references * len(windows(timed, size))


def plan(submissions: str, out: Path, shards: int, config: str, psweep: str, unconfined: bool,
         size: int, dry_run: bool) -> dict:
    if shards < 1:
        raise InputError(f"--shards: expected a positive number of shards, got {shards}")
    if size < 1:
        raise InputError(f"--window: expected submissions per timing window >= 1, got {size}")
    s = setup(submissions, config, psweep, unconfined)
    if shards > len(s.entries):
        raise InputError(f"--shards: {shards} shards for {len(s.entries)} submissions of "
                         f"{submissions}: expected at most one shard per submission")
    # A dry run draws and asks psweep in a folder of its own, removed after.
    scratch = Path(tempfile.mkdtemp(prefix="grade-slurm-")) if dry_run else out
    try:
        s.config = replace(s.config, scenes=draw_scenes(s.config.scenes, s.drawing[0],
                                                        Path(psweep).parent / "psim", scratch))
        say_drawn(s.config, s.drawing)
        say_timing_seed(s)
        estimates, references = estimates_s(s, scratch / "plan")
    finally:
        if dry_run:
            shutil.rmtree(scratch, ignore_errors=True)
    groups = split(estimates, shards)
    costs = [shard_estimate(g, estimates, references, size) for g in groups]
    one_machine = sum(estimates.values()) + references
    threads = [*s.config.judged_threads, *s.config.timed_threads]
    print(f"grade-slurm: {len(s.entries)} submissions of {submissions} in {shards} shards of "
          f"{', '.join(str(len(g)) for g in groups)} (balanced by the cost model's estimate), "
          f"timed in windows of up to {size} beside the references; the longest shard about "
          f"{duration(max(costs))}, {sum(costs) / 3600:.2f} node-hours in all, against about "
          f"{duration(one_machine)} on one machine (each task {max(threads)} CPUs)",
          file=sys.stderr)
    settings = {"submissions": str(Path(submissions).absolute()),
                "config": str(Path(config).absolute()), "psweep": str(Path(psweep).absolute()),
                "unconfined": unconfined, "timing_seed": list(s.timing_seed),
                "judging_seed": list(s.drawing), "window": size, "cpus": max(threads),
                "estimate_s": costs, "node_hours": round(sum(costs) / 3600, 4),
                "one_machine_s": one_machine, "shards": groups}
    if not dry_run:
        (out / PLAN).write_text(json.dumps(settings, indent=2) + "\n")
    return settings


# ---------------------------------------------------------------------------------------- task

def entry_record(e: Submission) -> dict:
    return {"name": e.name, "program": e.program, "path": str(e.path) if e.path else None,
            "note": e.note, "source": str(e.source) if e.source else None,
            "build_log": e.build_log}


def entry_of(record: dict) -> Submission:
    return Submission(record["name"], record["program"],
                      Path(record["path"]) if record["path"] else None, record["note"],
                      Path(record["source"]) if record["source"] else None,
                      record["build_log"])


def set_aside(folder: Path, node: str) -> None:
    """A window's unfinished rows from another node: kept beside it, never mixed with this
    node's (its times would be compared across nodes)."""
    k = 1
    while (aside := folder.with_name(f"{folder.name}.lost-{k}")).exists():
        k += 1
    folder.rename(aside)
    print(f"grade: {folder.name} was under way on another node: its rows kept in {aside.name}, "
          f"the window timed again from its start on {node}", file=sys.stderr)


def window_nodes(folder: Path) -> set[str]:
    try:
        runs = pd.read_csv(folder / "runs.csv", usecols=["node"], dtype=str)
    except (FileNotFoundError, ValueError, pd.errors.EmptyDataError):
        return set()
    return set(runs["node"].dropna())


def task(out: Path, index: int) -> None:
    plan_ = read_plan(out)
    groups = plan_["shards"]
    if not 1 <= index <= len(groups):
        raise InputError(f"shard {index}: expected 1 to {len(groups)} ({out / PLAN})")
    group = groups[index - 1]
    s = class_setup(plan_, out, set(group))
    total = sum(len(g) for g in groups)
    s.who = f"shard {index}/{len(groups)} ({len(group)} of the class's {total}): "
    shard = out / f"shard-{index}"
    node = node_name()
    s.say(f"on {node}")
    # A requeued task builds again: a build is confined and quick beside the grading, and the
    # build folder of the lost node may be half written.
    build_sources(s.entries, s.config, s.psweep, shard, s.unconfined)
    shard.mkdir(parents=True, exist_ok=True)
    (shard / "entries.json").write_text(json.dumps(
        [entry_record(e) for e in s.entries], indent=2) + "\n")
    timed_windows = []
    start = time.monotonic()
    stages = (len(s.config.scenes) if s.submissions else 0) + 1
    judging = judge(s, shard, stages, start, resume=True)
    timed = list(to_time(s, judging))
    write_meta(shard, s.config, *s.timing_seed, s.entries, s.drawing)
    timed_windows = windows(timed, plan_["window"])
    for k, names in enumerate(timed_windows, 1):
        folder = shard / "timing" / f"w-{k}"
        if (folder / DONE).is_file():
            s.say(f"[{stages}/{stages}] timing window {k}/{len(timed_windows)}: done before")
            continue
        if window_nodes(folder) - {node}:
            set_aside(folder, node)
        s.say(f"[{stages}/{stages}] timing window {k}/{len(timed_windows)} "
              f"({', '.join(s.shown[n] for n in names)}) on {node}, "
              f"{duration(time.monotonic() - start)} so far")
        s.sweep(timing_config(s.config, {n: s.submissions[n] for n in names},
                              s.timing_seed[0], s.lab),
                shard / "configs" / f"timing-w-{k}.json", folder, resume=True)
        (folder / DONE).write_text(node + "\n")
    (shard / DONE).write_text(json.dumps({"node": node, "windows": len(timed_windows)}) + "\n")
    s.say(f"done in {duration(time.monotonic() - start)}")


# --------------------------------------------------------------------------------------- merge

def shard_state(out: Path, index: int) -> tuple[list[Submission], list[Path]]:
    """A finished shard's entries and timing windows; InputError naming what it lacks and how
    to finish it."""
    shard = out / f"shard-{index}"
    done = shard / DONE
    if not done.is_file():
        raise InputError(f"{shard} is not finished (no {DONE} marker): run its task again, "
                         f"`/usr/bin/python3 -m analysis grade-slurm task {out} {index}` (it "
                         "resumes), then merge")
    entries = [entry_of(r) for r in json.loads((shard / "entries.json").read_text())]
    count = json.loads(done.read_text())["windows"]
    return entries, [shard / "timing" / f"w-{k}" for k in range(1, count + 1)]


def nodes_of(results: list, program: str) -> str:
    """The nodes the runs of `program` in these sweeps ran on."""
    nodes = set()
    for r in results:
        nodes |= set(r.runs.loc[r.runs["engine"] == program, "node"].dropna().astype(str))
    return ", ".join(sorted(nodes))


def merge(out: Path) -> pd.DataFrame:
    plan_ = read_plan(out)
    groups = plan_["shards"]
    s = class_setup(plan_, out)
    entries, judging, timings, graded = [], [], [], []
    for index in range(1, len(groups) + 1):
        mine, folders = shard_state(out, index)
        shard = out / f"shard-{index}"
        judged = []
        for scene in s.config.scenes if any(e.path for e in mine) else []:
            judged.append(load_results(shard / "judge" / scene.name))
            judged[-1].runs["scene_file"] = scene.shown
        timed = [load_results(folder) for folder in folders]
        graded += [{"name": e.shown, "shard": index, "judged_on": nodes_of(judged, e.program),
                    "timed_on": nodes_of(timed, e.program)} for e in mine]
        entries += mine
        judging += judged
        timings += timed
    expected = sorted(n for g in groups for n in g)
    got = sorted(e.name for e in entries)
    if got != expected:
        raise InputError(f"the shards' entries are not the plan's: missing "
                         f"{sorted(set(expected) - set(got))[:5]}, unexpected "
                         f"{sorted(set(got) - set(expected))[:5]}")
    by_name = {e.name: e for e in entries}
    s.entries = [by_name[e.name] for e in s.entries]
    if not timings:
        raise InputError("no shard timed anything: no timing window to take the references from")
    programs = {}
    for j in judging:
        programs.update(j.meta.get("programs", {}))
    write_meta(out, s.config, *s.timing_seed, s.entries, s.drawing)
    meta = json.loads((out / "meta.json").read_text())
    meta["shards"] = [{"index": i, "submissions": g,
                       "done": json.loads((out / f"shard-{i}" / DONE).read_text())}
                      for i, g in enumerate(groups, 1)]
    (out / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")
    write_csv(pd.DataFrame(graded), out / "nodes.csv")
    return score(s, out, judging, timings, programs,
                 f"{len(s.entries)} submissions of {plan_['submissions']}")


# ------------------------------------------------------------------------------------ progress

def progress(out: Path) -> str:
    """One line for the whole class: the submissions whose grade is final (their timing window
    done, or not to be timed), per shard, and the estimate of what is left."""
    plan_ = read_plan(out)
    groups, size = plan_["shards"], plan_["window"]
    finished, parts, left = 0, [], 0.0
    for index, (group, cost) in enumerate(zip(groups, plan_["estimate_s"]), 1):
        shard = out / f"shard-{index}"
        if (shard / DONE).is_file():
            done = len(group)
        else:
            windows_done = len(list((shard / "timing").glob(f"w-*/{DONE}")))
            done = min(len(group), windows_done * size)
        finished += done
        left += cost * (1 - done / len(group)) if group else 0
        parts.append(f"shard {index} {done}/{len(group)}")
    total = sum(len(g) for g in groups)
    return (f"grade-slurm: {finished} of {total} submissions graded ({'; '.join(parts)}), about "
            f"{duration(left)} of node time left by the estimate")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description="A class graded over a Slurm cluster: plan, a task per shard, the merge.",
        epilog="docs/programs.md, \"A class on a Slurm cluster\". Exit 2 on bad input.")
    sub = parser.add_subparsers(dest="step", required=True)
    p = sub.add_parser("plan", help="draw the class's scenes and seeds, split it, write "
                                    "OUT/grade-slurm.json")
    p.add_argument("submissions", metavar="DIR")
    p.add_argument("--out", required=True)
    p.add_argument("--shards", type=int, required=True)
    p.add_argument("--window", type=int, default=WINDOW, help="submissions per timing window "
                   f"(default {WINDOW})")
    p.add_argument("--config", default="configs/grade.json")
    p.add_argument("--psweep", default="build/psweep")
    p.add_argument("--unconfined", action="store_true")
    p.add_argument("--dry-run", action="store_true", help="say the split and the node-hours, "
                   "write nothing")
    t = sub.add_parser("task", help="grade shard I into OUT/shard-I (resumes)")
    t.add_argument("out", metavar="OUT")
    t.add_argument("index", metavar="I", type=int)
    m = sub.add_parser("merge", help="score every shard as one class into OUT")
    m.add_argument("out", metavar="OUT")
    g = sub.add_parser("progress", help="the whole class's progress")
    g.add_argument("out", metavar="OUT")
    args = parser.parse_args(argv)
    out = Path(args.out)
    steps = {"plan": lambda: plan(args.submissions, out, args.shards, args.config, args.psweep,
                                  args.unconfined, args.window, args.dry_run),
             "task": lambda: task(out, args.index),
             "merge": lambda: (merge(out), print(progress(out), file=sys.stderr)),
             "progress": lambda: print(progress(out))}
    return exit_status("grade-slurm", steps[args.step])
