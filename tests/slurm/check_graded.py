"""make test-slurm's verdict on a class graded through Slurm (`make grade-slurm`) against the same
class graded on this machine (`make grade`): every verdict and judging point identical, the speed
points within the spread the grades state (grades.csv's speed_spread, the points the medians
would give against the least times'), the class report's counts those of grades.csv, every
submission graded on a node Slurm's records put its task on, and the hostile submissions
contained.

usage: check_graded.py LOCAL_OUT SLURM_OUT RECORDS VICTIMS [--slow NODE] [--lost NODE]
  RECORDS   `scontrol -o show job ARRAY_JOB_ID` after the jobs ended
  VICTIMS   make_class.py's record of what the hostile submissions attack
  --slow    the node whose CPU quota made its runs slower: its references' raw times are
            longer, and its submissions' speed points still agree (raw times would not)
  --lost    the node killed mid-grading: its task was requeued, the timing windows it finished
            there kept, not run again
"""
import argparse
import csv
import hashlib
import json
import os
import re
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
from analysis.grade.curve import read_curve  # noqa: E402

SAME = ["kind", "verdict", "verdict_T1", "scene", "corner", "wall_before_end", "head_on",
        "timing"]
PASSING = {"exact", "consistent", "ambiguous"}


def table(path):
    with open(path, newline="") as f:
        return {row["name"]: row for row in csv.DictReader(f)}


def records(path):
    tasks = {}
    for line in Path(path).read_text().splitlines():
        fields = dict(re.findall(r"(\w+)=(\S*)", line))
        if "ArrayTaskId" in fields:
            tasks[int(fields["ArrayTaskId"])] = fields
    return tasks


def number(text):
    return float(text) if text not in ("", None) else float("nan")


def main() -> int:
    parser = argparse.ArgumentParser()
    for name in ("local", "slurm", "records", "victims"):
        parser.add_argument(name)
    parser.add_argument("--slow")
    parser.add_argument("--lost")
    args = parser.parse_args()
    local, slurm = Path(args.local), Path(args.slurm)
    problems = []
    a, b = table(local / "scoreboard.csv"), table(slurm / "scoreboard.csv")
    ga, gb = table(local / "grades.csv"), table(slurm / "grades.csv")
    if set(a) != set(b) or set(ga) != set(gb):
        problems.append(f"other names: {sorted(set(a) ^ set(b))} {sorted(set(ga) ^ set(gb))}")
    for name in sorted(set(a) & set(b)):
        for column in SAME:
            if a[name][column] != b[name][column]:
                problems.append(f"{name}: {column} {a[name][column]!r} here, "
                                f"{b[name][column]!r} through Slurm")
    plan = json.loads((slurm / "grade-slurm.json").read_text())
    config = json.loads(Path(plan["config"]).read_text())
    curve = read_curve(config["timing"], "timing")
    speed_points = config.get("points", {}).get("speed", 30)
    disagree, raw_apart, on_slow = [], 0, 0
    for name in sorted(set(ga) & set(gb)):
        x, y = ga[name], gb[name]
        for column in ("judging_score", "max_score"):
            if x[column] != y[column]:
                problems.append(f"{name}: {column} {x[column]} here, {y[column]} through Slurm")
        gap = abs(number(x["speed_score"]) - number(y["speed_score"]))
        spread = number(x["speed_spread"]) + number(y["speed_spread"])
        if gap > spread + 1e-6:
            disagree.append(f"{name} {x['speed_score']} here, {y['speed_score']} through Slurm "
                            f"(spreads {x['speed_spread']} and {y['speed_spread']})")
        if args.slow and b[name]["node"] == args.slow and number(y["speed_score"]) > 0:
            on_slow += 1
            # Its time on the slow node against the reference timed here: the raw comparison.
            raw = speed_points * curve.time_share(
                number(b[name]["time_T1_s"]) / number(a[name]["reference_s"]))
            if abs(raw - number(y["speed_score"])) > spread + 1e-6:
                raw_apart += 1
    # Timings on shared cores are noisy: the points agree within the stated spread for all but
    # a few submissions (a run slowed by another agent's build in one window and not the other
    # is not the node's doing).
    timed = sum(number(g["speed_score"]) > 0 for g in gb.values())
    if len(disagree) > max(1, timed // 10):
        problems.append(f"{len(disagree)} of {timed} speed scores beyond their spread: "
                        + "; ".join(disagree[:5]))
    if args.slow:
        refs = [(number(r["reference_s"]), r["node"]) for r in b.values() if r["reference_s"]]
        slow = [t for t, node in refs if node == args.slow]
        fast = [t for t, node in refs if node != args.slow]
        if not slow or not fast:
            problems.append(f"no reference timed on {args.slow} and elsewhere: {refs}")
        elif statistics.median(slow) < 1.25 * statistics.median(fast):
            problems.append(f"the references on {args.slow} ({statistics.median(slow):.4g} s) "
                            f"are not slower than elsewhere ({statistics.median(fast):.4g} s)")
        elif on_slow and raw_apart < on_slow / 2:
            problems.append(f"raw times would agree too: {raw_apart} of {on_slow} apart")
        else:
            print(f"check_graded: references {statistics.median(slow):.4g} s on {args.slow}, "
                  f"{statistics.median(fast):.4g} s elsewhere; {on_slow} submissions scored "
                  f"there, {raw_apart} of them apart by raw times, "
                  f"{len(disagree)} of {timed} beyond their spread by ratios", file=sys.stderr)
    # The class report counts what grades.csv says.
    page = (slurm / "class.md").read_text()
    if f"{len(gb)} submissions: median" not in page:
        problems.append(f"class.md does not count {len(gb)} submissions")
    programs = [r for r in b.values() if r["kind"] == "program"]
    for scene in ("corner", "wall_before_end", "head_on"):
        row = next((line for line in page.splitlines() if line.startswith(f"| drawn/{scene}.in")),
                   None)
        cells = [c.strip() for c in row.strip("|").split("|")] if row else []
        counts = [sum(r[scene] == v for r in programs) for v in
                  ("exact", "consistent", "ambiguous", "violations", "malformed", "failed")]
        if [int(c) for c in cells[1:7]] != counts:
            problems.append(f"class.md's {scene} row {cells[1:7]}, the board {counts}")
    # Every submission graded on a node its task's record names (a requeued task: its last).
    tasks = records(args.records)
    nodes = table(slurm / "nodes.csv")
    for name, row in nodes.items():
        record = tasks.get(int(row["shard"]))
        if record is None:
            problems.append(f"{name}: no record of shard {row['shard']}")
        elif row["timed_on"] and row["timed_on"] not in (record["NodeList"], args.lost):
            problems.append(f"{name}: timed on {row['timed_on']}, its task's record says "
                            f"{record['NodeList']}")
    if args.lost:
        requeued = [i for i, r in tasks.items() if r.get("Restarts", "0") != "0"]
        if len(requeued) != 1:
            problems.append(f"expected one requeued task, got {requeued}")
        else:
            shard = slurm / f"shard-{requeued[0]}"
            kept = [p.parent.name for p in (shard / "timing").glob("w-*/done")
                    if p.read_text().strip() == args.lost]
            if not kept:
                problems.append(f"shard {requeued[0]}: no timing window finished on "
                                f"{args.lost} was kept")
            judge_rows = [line for p in (shard / "judge").glob("*/runs.csv")
                          for line in p.read_text().splitlines()[1:]]
            ids = [line.split(",")[:2] for line in judge_rows]
            if len(ids) != len({tuple(i) for i in ids}):
                problems.append(f"shard {requeued[0]}: a judging run recorded twice")
            print(f"check_graded: shard {requeued[0]} lost {args.lost}, requeued on "
                  f"{tasks[requeued[0]]['NodeList']}: windows {', '.join(sorted(kept))} kept "
                  "from the lost node", file=sys.stderr)
    # The hostile submissions: contained, judged alike both ways, never passing.
    victims = json.loads(Path(args.victims).read_text())
    for path, digest in victims["files"].items():
        if hashlib.sha256(Path(path).read_bytes()).hexdigest() != digest:
            problems.append(f"{path} was changed by a submission")
    problems += [f"{path} was written by a submission" for path in victims["absent"]
                 if Path(path).exists()]
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if victims["token"] in cmdline and "check_graded" not in cmdline:
            problems.append(f"a process a submission left is alive: {pid} {cmdline}")
    for name in ("forger", "lingerer"):
        if b[name]["verdict"] in PASSING:
            problems.append(f"{name} passed: {b[name]['verdict']}")
    for line in problems:
        print(f"check_graded: {line}", file=sys.stderr)
    if not problems:
        print(f"check_graded: ok: {len(gb)} submissions, {len(tasks)} shards on "
              f"{', '.join(sorted({r['NodeList'] for r in tasks.values()}))}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
