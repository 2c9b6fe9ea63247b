"""make test-slurm's verdict: the merged result of the Slurm sweep holds exactly the configurations,
repetitions and final-state hashes of the same config swept locally, and its meta.json names both
shards, their hosts and Slurm ids.

usage: check_merged.py LOCAL_DIR MERGED_DIR ARRAY_JOB_ID MERGE_JOB_ID
"""
import csv
import json
import sys
from pathlib import Path


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    local, merged, array_id, merge_id = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3], sys.argv[4]
    problems = []
    local_runs, merged_runs = rows(local / "runs.csv"), rows(merged / "runs.csv")
    key = lambda r: (r["config_id"], r["rep"], r["status"], r["state_hash"])
    if sorted(map(key, local_runs)) != sorted(map(key, merged_runs)):
        problems.append(f"runs differ: local {sorted(map(key, local_runs))}\n  merged {sorted(map(key, merged_runs))}")
    if any(r["status"] != "ok" or not r["state_hash"] for r in merged_runs):
        problems.append("a merged run is not ok or has no state hash")
    ids = lambda d: sorted(r["config_id"] for r in rows(d / "summary.csv"))
    if ids(local) != ids(merged):
        problems.append(f"summary.csv configurations differ: {ids(local)} vs {ids(merged)}")

    meta = json.loads((merged / "meta.json").read_text())
    shards = meta.get("merged", {}).get("shards", [])
    if sorted(s["shard"] for s in shards) != ["1/2", "2/2"]:
        problems.append(f"meta.json merged.shards: {shards}")
    for s in shards:
        slurm = s.get("slurm") or {}
        if not s.get("host") or slurm.get("array_job_id") != array_id or not slurm.get("array_task_id"):
            problems.append(f"shard {s.get('shard')}: host or Slurm ids missing: {s}")
    if (meta.get("slurm") or {}).get("job_id") != merge_id:
        problems.append(f"meta.json slurm (the merge job): {meta.get('slurm')}, expected job {merge_id}")
    if meta["merged"]["missing_runs"] or meta["merged"]["duplicated_runs"]:
        problems.append(f"missing or duplicated runs: {meta['merged']}")
    if not list(merged.glob("plots/*.png")):
        problems.append("the merge job drew no plots")

    for p in problems:
        print(f"test-slurm: FAIL: {p}", file=sys.stderr)
    if not problems:
        print(f"test-slurm: ok: {len(merged_runs)} runs of {len(ids(merged))} configurations, "
              f"state hashes equal to the local sweep's; shards on {sorted({s['host'] for s in shards})}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
