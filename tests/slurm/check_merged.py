"""make test-slurm's verdict on one Slurm sweep: its merged folder holds exactly the runs of the
same config swept locally (configurations, repetitions, final-state hashes; each once), its shards
ran on at least two nodes by Slurm's own job records, and every row and meta.json name the node
the row ran on. With --lost NODE, the shard that ran on NODE when it was lost was requeued,
kept the rows it had written there and finished the rest on another node.

usage: check_merged.py LOCAL_DIR SLURM_OUT RECORDS [--lost NODE]
  SLURM_OUT  submit.sh's OUT (OUT/slurm/jobs: the array and merge job ids)
  RECORDS    `scontrol -o show job ARRAY_JOB_ID` after the jobs ended: one line per array task
"""
import argparse
import csv
import json
import re
import sys
from collections import Counter
from pathlib import Path


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def task_records(path):
    """{array task id: its record's fields} (ArrayTaskId, NodeList, Restarts, JobState, ...)."""
    tasks = {}
    for line in Path(path).read_text().splitlines():
        fields = dict(re.findall(r"(\w+)=(\S*)", line))
        if "ArrayTaskId" in fields:
            tasks[fields["ArrayTaskId"]] = fields
    return tasks


def shard_problems(folder, task, record, entry, array_id, lost):
    """One array task against Slurm's record of it and meta.json's entry for its shard; `lost`:
    the node it lost (Slurm requeued it), else None."""
    problems = []
    shard_rows = rows(folder / "runs.csv")
    runs = Counter((r["config_id"], r["rep"]) for r in shard_rows)
    if max(runs.values(), default=1) > 1:
        problems.append(f"shard {task} recorded runs more than once: {[k for k, n in runs.items() if n > 1]}")
    if record.get("JobState") != "COMPLETED":
        problems.append(f"task {task} ended {record.get('JobState')}")
    if (entry.get("slurm") or {}).get("array_job_id") != array_id:
        problems.append(f"meta.json's shard {task}: Slurm ids {entry.get('slurm')}")
    ran_on = [r["node"] for r in shard_rows]
    if entry.get("nodes") != sorted(set(ran_on)):
        problems.append(f"meta.json's shard {task}: nodes {entry.get('nodes')}, its rows {set(ran_on)}")
    # The rows written before the loss first, then the rest on the node Slurm requeued it to.
    k = ran_on.count(lost)
    if ran_on[:k] != [lost] * k or set(ran_on[k:]) != {record["NodeList"]} or (lost and not k):
        problems.append(f"shard {task}: rows ran on {ran_on}; Slurm's record: {record['NodeList']}"
                        + (f" after losing {lost}" if lost else ""))
    if lost and not json.loads((folder / "meta.json").read_text()).get("resumed"):
        problems.append(f"requeued shard {task}: its meta.json records no resumed session")
    return problems


def check(local, out, records, lost):
    problems = []
    array_id, merge_id = (out / "slurm" / "jobs").read_text().split()
    local_runs, merged_runs = rows(local / "runs.csv"), rows(out / "runs.csv")
    key = lambda r: (r["config_id"], r["rep"], r["status"], r["state_hash"])
    local_keys, merged_keys = Counter(map(key, local_runs)), Counter(map(key, merged_runs))
    if local_keys != merged_keys:
        problems.append(f"{len(merged_runs)} runs, {len(local_runs)} locally; only local: "
                        f"{sorted(local_keys - merged_keys)[:3]}; only merged, or more than once: "
                        f"{sorted(merged_keys - local_keys)[:3]}")
    if any(r["status"] != "ok" or not r["state_hash"] or not r["node"] for r in merged_runs):
        problems.append("a merged run is not ok, or has no state hash or node")

    meta = json.loads((out / "meta.json").read_text())
    merged = meta.get("merged", {})
    shards = {s["shard"].split("/")[0]: s for s in merged.get("shards", [])}
    tasks = task_records(records)
    if sorted(shards) != sorted(tasks) or not tasks:
        problems.append(f"meta.json's shards {sorted(shards)} are not the array's tasks {sorted(tasks)}")
    if merged.get("missing_runs") or merged.get("duplicated_runs"):
        problems.append(f"missing or duplicated runs: {merged}")
    if (meta.get("slurm") or {}).get("job_id") != merge_id:
        problems.append(f"meta.json slurm (the merge job): {meta.get('slurm')}, expected job {merge_id}")
    if sorted(merged.get("nodes", [])) != sorted({r["node"] for r in merged_runs}):
        problems.append(f"meta.json merged.nodes {merged.get('nodes')} are not the rows' nodes")
    if not list(out.glob("plots/*.png")):
        problems.append("the merge job drew no plots")

    nodes = {t["NodeList"] for t in tasks.values()}
    if len(nodes) < 2:
        problems.append(f"Slurm ran every shard on {nodes}: the test needs two nodes or more")
    requeued = [task for task, record in tasks.items() if record.get("Restarts", "0") != "0"]
    if (lost is not None) != (len(requeued) == 1):
        problems.append(f"requeued tasks {requeued}, expected {'one' if lost else 'none'}")
    for task, record in sorted(tasks.items()):
        problems += shard_problems(out / f"shard-{task}", task, record, shards.get(task, {}), array_id,
                                   lost if task in requeued else None)

    for p in problems:
        print(f"test-slurm: FAIL: {out.name}: {p}", file=sys.stderr)
    if not problems:
        where = ", ".join(f"{t} on {r['NodeList']}" + (f" (requeued from {lost})" if t in requeued else "")
                          for t, r in sorted(tasks.items()))
        print(f"test-slurm: ok: {out.name}: {len(merged_runs)} runs of "
              f"{len({r['config_id'] for r in merged_runs})} configurations, each once, state hashes "
              f"equal to the local sweep's; shards {where}", file=sys.stderr)
    return not problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("local", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("records", type=Path)
    parser.add_argument("--lost", help="the node lost while a shard ran on it")
    args = parser.parse_args()
    return 0 if check(args.local, args.out, args.records, args.lost) else 1


if __name__ == "__main__":
    sys.exit(main())
