"""The class report (analysis/grade/classreport.py): OUT/class.md and .html of a graded class,
its counts those of the scoreboard, its byte-identical groups the wrong copies alone."""
import csv
import json
import shutil
import subprocess

from build_path import BUILD
from entry_point import ROOT
from test_confinement import quick_config, write


def test_the_class_report_counts_what_the_scoreboard_says(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    for name in ("alice", "bob", "carol"):  # correct: the reference's text, never grouped
        shutil.copy(BUILD / "plain_allpairs", folder / name)
    for name in ("dave", "erin"):  # the same wrong program twice
        shutil.copy(BUILD / "check_programs" / "wall_tolerance", folder / name)
    shutil.copy(BUILD / "check_programs" / "drop_last", folder / "frank")
    write(folder, "grace", "#!/bin/sh\nexit 3\n")
    # corner and head_on, and a wall hit a few ulps before the step's end: the wrong copies' rule
    config = quick_config(tmp_path)
    settings = json.loads(config.read_text())
    settings["judging"]["scenes"] += [
        s for s in json.loads((ROOT / "configs" / "grade.json").read_text())["judging"]["scenes"]
        if s["file"] == "scenes/wall_before_end.in"]
    config.write_text(json.dumps(settings))
    out = tmp_path / "out"
    done = subprocess.run(
        ["/usr/bin/python3", "-m", "analysis", "grade", str(folder), "--out", str(out),
         "--config", str(config), "--psweep", str(BUILD / "psweep")],
        capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    page = (out / "class.md").read_text()
    assert (out / "class.html").is_file() and (out / "class" / "scores.png").is_file()
    assert "7 submissions: median" in page, page
    with open(out / "scoreboard.csv", newline="") as f:
        board = [r for r in csv.DictReader(f) if r["kind"] == "program"]
    # Each judging scene's row: the scoreboard's verdicts, counted.
    for scene in ("corner", "head_on", "wall_before_end"):
        row = next(line for line in page.splitlines() if line.startswith(f"| scenes/{scene}.in")
                   or line.startswith(f"| drawn/{scene}.in"))
        cells = [c.strip() for c in row.strip("|").split("|")]
        for k, verdict in enumerate(("exact", "consistent", "ambiguous", "violations",
                                     "malformed", "failed")):
            assert int(cells[1 + k]) == sum(r[scene] == verdict for r in board), (scene, row)
    wall = next(line for line in page.splitlines() if "wall_before_end.in" in line)
    assert "wall hit missed (2)" in wall and "[dave](reports/dave.html), [erin]" in wall, wall
    groups = page.split("## Byte-identical outputs")[1]
    assert "- dave, erin" in groups and "alice" not in groups, groups
    # The timing's noise: the reference's runs, under its name and again (two repetitions each).
    noise = page.split("## The timing's noise")[1].split("##")[0]
    row = next(line for line in noise.splitlines() if line.startswith("| timing |"))
    assert [c.strip() for c in row.strip("|").split("|")][:3] == ["timing", "1", "4"], row


def test_the_noise_table_counts_the_references_slowed_runs_per_window_and_T(tmp_path):
    import pandas as pd
    from analysis.grade.classreport import noise_table
    runs = [("plain_allpairs", "shard-1/timing/w-1", 1.0, s) for s in (1.0, 1.1, 1.2, 1.5)]
    runs += [("plain_allpairs", "shard-2/timing/w-1", 1.0, s) for s in (2.0, 2.0, 2.0, 2.0)]
    runs += [("plain_allpairs", "shard-2/timing/w-1", 2.0, s) for s in (1.0, 1.3)]
    runs += [("alice", "shard-1/timing/w-1", 1.0, 9.0), ("plain_allpairs", "shard-1", 1.0, None)]
    timed = pd.DataFrame([{"engine": e, "results": str(tmp_path / w), "T": t, "process_s": s,
                           "status": "ok"} for e, w, t, s in runs])
    table = noise_table(timed, "plain_allpairs", 2, tmp_path)
    assert table.to_dict("records") == [
        {"window": "shard-1/timing/w-1", "T": 1.0, "runs": 4, "least (s)": 1.0,
         "slowed": "50%", "all 2 of a submission slowed": "25.0%"},
        {"window": "shard-2/timing/w-1", "T": 1.0, "runs": 4, "least (s)": 2.0,
         "slowed": "0%", "all 2 of a submission slowed": "0.0%"},
        {"window": "shard-2/timing/w-1", "T": 2.0, "runs": 2, "least (s)": 1.0,
         "slowed": "50%", "all 2 of a submission slowed": "25.0%"}]
