"""make test-slurm's class: a folder of submissions as a course gets them, and a grade config small
enough that the class grades in about a minute on one machine.

usage: make_class.py BUILD DIR CONFIG VICTIMS
  DIR      the submissions, made here: 24 copies of plain_allpairs (correct, byte-identical),
           each broken build of tests/check (build/check_programs/) once and wall_tolerance three
           times (byte-identical wrong outputs), a program that hangs, one that crashes, and two
           hostile ones of tests/python/test_confinement.py (a forger that writes into psim, the
           repository, the results and another submission; a lingerer that leaves processes and
           a daemon behind, each named by the token below)
  CONFIG   written here: configs/grade.json on three judging scenes at T = 1, 2 s a judging run
           (the hang's cost), a timing scene of N = 1000, S = 60 at T = 1 (some 0.1 s a run, the
           process's start a fifth of it), 5 repetitions after a
           warm-up, both seeds pinned so that `make grade` and `make grade-slurm` judge the same
           scenes, busy runs counted (the nodes share this machine's cores)
  VICTIMS  written here: a JSON of the files the forger attacks and their sha256, for
           check_graded.py
"""
import hashlib
import json
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TOKEN = "grade-slurm-hostile-4711"  # $0 of every process the lingerer leaves


def write(path: Path, text: str) -> None:
    path.write_text(text)
    path.chmod(0o755)


def main(build: str, folder: str, config: str, victims: str) -> None:
    build, folder = Path(build).absolute(), Path(folder).absolute()
    folder.mkdir(parents=True)
    for i in range(24):
        shutil.copy(build / "plain_allpairs", folder / f"student{i:02}")
    broken = sorted(p for p in (build / "check_programs").iterdir() if p.is_file())
    for program in broken:
        shutil.copy(program, folder / f"broken_{program.name}")
    for i in (2, 3):
        shutil.copy(build / "check_programs" / "wall_tolerance", folder / f"copied_wall_{i}")
    write(folder / "hangs", "#!/bin/sh\nexec sleep 3600\n")
    write(folder / "crashes", "#!/bin/sh\nkill -SEGV $$\n")
    psim = build / "psim"
    outside = folder.parent / "outside.txt"
    outside.write_text("the grader's own file\n")
    target = folder / "student00"
    write(folder / "forger", f"""#!/bin/sh
cp /bin/true {psim} 2>/dev/null; printf '#!/bin/sh\\necho exact\\n' > {psim} 2>/dev/null
echo forged > {ROOT}/forged-by-a-submission 2>/dev/null
echo forged > {folder.parent}/forged-by-a-submission 2>/dev/null
echo forged > {target} 2>/dev/null
echo appended >> {outside} 2>/dev/null
if [ -x {psim} ]; then exec {psim} --engine brute; fi
exit 1
""")
    write(folder / "lingerer", f"""#!/bin/sh
for i in 1 2 3; do sh -c 'sleep 3600; :' {TOKEN} & done
setsid sh -c 'sleep 3600; :' {TOKEN} &
exit 0
""")
    Path(victims).write_text(json.dumps({
        "files": {str(p): hashlib.sha256(p.read_bytes()).hexdigest()
                  for p in (psim, target, outside)},
        "absent": [str(ROOT / "forged-by-a-submission"),
                   str(folder.parent / "forged-by-a-submission")],
        "token": TOKEN}, indent=2) + "\n")
    settings = json.loads((ROOT / "configs" / "grade.json").read_text())
    keep = ("scenes/corner.in", "scenes/wall_before_end.in", "scenes/head_on.in")
    settings["judging"].update(scenes=[s for s in settings["judging"]["scenes"]
                                       if s["file"] in keep], T=[1], timeout_s=2, seed=54)
    settings["timing"].update(scene={"N": 1000, "L": 20000, "r": 1, "S": 60, "seed": 54}, T=[1],
                              repetitions=5, warmup=1, timeout_s=30,
                              quiet={"wait_s": 0, "busy_runs": "count"})
    Path(config).write_text(json.dumps(settings, indent=2) + "\n")
    print(f"make_class: {len(list(folder.iterdir()))} submissions in {folder}", file=sys.stderr)


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
