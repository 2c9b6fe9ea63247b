"""make test-slurm's verdict on the run of ranks across nodes: one psweep run of the mpi engine at
P = 4, started by the config's own launcher inside one Slurm allocation of several nodes, ended ok
with the final state of the local sweep's brute run on the same scene (every engine gives brute's
bits at every P), its ranks on at least two nodes by their own count (the `nodes` metric: each
rank's Slurm node name) and by Slurm's record of the job.

usage: check_ranks.py LOCAL_DIR RANKS_OUT RECORD
  LOCAL_DIR  the local sweep of tiny.json, whose brute run of the same scene is the reference
  RANKS_OUT  psweep's folder of tests/slurm/ranks.json, run inside the allocation
  RECORD     `scontrol -o show job JOB_ID` of that allocation after it ended
"""
import argparse
import json
import re
import sys
from pathlib import Path

from check_merged import rows

# The columns that make a scene: equal values, equal initial state.
SCENE = ["N", "L", "r", "S", "slow_factor", "seed", "speed_min", "speed_max", "scene_file", "wall_stop"]


def check(local, out, record_path):
    problems = []
    record = dict(re.findall(r"(\w+)=(\S*)", record_path.read_text()))
    runs = rows(out / "runs.csv")
    if len(runs) != 1 or runs[0]["engine"] != "mpi":
        problems.append(f"expected one mpi run, got {[(r['engine'], r['P']) for r in runs]}")
        runs = [r for r in runs if r["engine"] == "mpi"][:1]
    run = runs[0] if runs else {}
    if run.get("status") != "ok":
        problems.append(f"the run ended {run.get('status')}: {run.get('error')}")
    if run.get("ranks") != run.get("P") or run.get("P") != "4":
        problems.append(f"P = {run.get('P')}, and the engine counted {run.get('ranks')} ranks")
    if int(run.get("nodes") or 0) < 2:
        problems.append(f"the ranks ran on {run.get('nodes') or 'no'} node(s): the test needs two or more")
    if record.get("JobState") != "COMPLETED" or int(record.get("NumNodes", "0")) < 2:
        problems.append(f"Slurm's record: {record.get('JobState')} on {record.get('NumNodes')} "
                        f"nodes ({record.get('NodeList')})")
    launcher = json.loads((out / "meta.json").read_text()).get("launcher")
    config = json.loads(Path("tests/slurm/ranks.json").read_text())["launcher"]
    if launcher != config:
        problems.append(f"meta.json's launcher {launcher} is not the config's {config}")

    scene = [run.get(c) for c in SCENE]
    reference = [r for r in rows(local / "runs.csv")
                 if r["engine"] == "brute" and r["status"] == "ok" and [r[c] for c in SCENE] == scene]
    hashes = {r["state_hash"] for r in reference}
    if not hashes:
        problems.append(f"the local sweep has no brute run of the scene {dict(zip(SCENE, scene))}")
    elif hashes != {run.get("state_hash")}:
        problems.append(f"state_hash {run.get('state_hash')}, the local brute runs' {sorted(hashes)}")

    for p in problems:
        print(f"test-slurm: FAIL: ranks: {p}", file=sys.stderr)
    if not problems:
        print(f"test-slurm: ok: ranks: mpi P = {run['P']}, T = {run['T']}: {run['ranks']} ranks on "
              f"{run['nodes']} nodes of the allocation {record['NodeList']} (psweep on "
              f"{run['node']}), state_hash {run['state_hash']} = the local brute run's, "
              f"{float(run['wall_s']):.2f} s", file=sys.stderr)
    return not problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("local", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("record", type=Path)
    args = parser.parse_args()
    return 0 if check(args.local, args.out, args.record) else 1


if __name__ == "__main__":
    sys.exit(main())
