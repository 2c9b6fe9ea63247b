"""make grade (analysis/grade, docs/programs.md "Grading many submissions") end to end with the
real psweep and psim: a folder of submissions built by `make build` (plain_allpairs as `plain`,
and two broken builds of it), a crashing script and a file that is not executable, judged on every
judging scene of configs/grade.json and timed on a tiny scene instead of the 2019 default (the
config's timing section replaced, so the run takes seconds).
"""
import csv
import json
import re
import shutil
import subprocess

import pytest

from analysis.grade.curve import SpeedCurve
from build_path import BUILD
from entry_point import ROOT, run_tool

SUBMISSIONS = {"plain": BUILD / "plain_allpairs",
               "wall_tolerance": BUILD / "check_programs" / "wall_tolerance",
               "nan": BUILD / "check_programs" / "nan"}


def quick_config(folder):
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    # Busy runs counted: on a shared machine the one repetition of a program could be busy and
    # leave no time to grade (their exclusion: test_grade_rules.py and test_harness_psweep.py).
    config["timing"].update(scene={"N": 40, "L": 2000, "r": 1, "S": 20, "seed": 7},
                            repetitions=1, warmup=0, quiet={"busy_runs": "count"})
    path = folder / "grade_quick.json"
    path.write_text(json.dumps(config))
    return path


def grade(*args):
    return run_tool("grade", *args, "--psweep", BUILD / "psweep", timeout=300)


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("grade")
    folder = root / "submissions"
    folder.mkdir()
    for name, built in SUBMISSIONS.items():
        assert built.is_file(), f"{built} is missing: build first (make build)"
        shutil.copy(built, folder / name)
    (folder / "crash.sh").write_text("#!/bin/sh\nkill -SEGV $$\n")
    (folder / "crash.sh").chmod(0o755)
    (folder / "not_executable").write_text("#!/bin/sh\n")
    (folder / ".hidden").write_text("not a submission\n")
    out = root / "out"
    done = grade(folder, "--out", out, "--config", quick_config(root))
    with open(out / "scoreboard.csv", newline="") as f:
        board = {row["name"]: row for row in csv.DictReader(f)}
    return done, out, board


def test_the_grading_runs_to_its_end_whatever_the_submissions_do(graded):
    done, out, board = graded
    assert done.returncode == 0, done.stderr
    assert set(board) == {"plain_allpairs", "brute", "auto", "plain", "wall_tolerance", "nan",
                          "crash.sh", "not_executable"}
    assert re.search(r"\| plain \| program \| [\d.]+ \| exact \|", done.stdout)
    assert "not timed, no judging run ended ok: crash.sh, not_executable" in done.stderr


def test_correct_before_violating_before_failed(graded):
    _, _, board = graded
    rank = {name: int(row["rank"]) for name, row in board.items()}
    assert sorted(rank.values()) == list(range(1, 9))
    verdicts = {name: row["verdict"] for name, row in board.items()}
    assert verdicts == {"brute": "exact", "auto": "exact", "plain_allpairs": "exact",
                        "plain": "exact",
                        "wall_tolerance": "violations", "nan": "violations",
                        "crash.sh": "failed", "not_executable": "failed"}
    exact = [rank[n] for n, v in verdicts.items() if v == "exact"]
    violations = [rank[n] for n, v in verdicts.items() if v == "violations"]
    failed = [rank[n] for n, v in verdicts.items() if v == "failed"]
    assert max(exact) < min(violations) and max(violations) < min(failed)
    assert board["plain"]["kind"] == "program" and board["brute"]["kind"] == "engine"
    # the lab's reference program: judged and timed as a submission is, the lab's row
    assert board["plain_allpairs"]["kind"] == "lab" and board["plain_allpairs"]["score"] == ""
    assert board["plain_allpairs"]["report"] == "" and board["plain_allpairs"]["timing"] == "exact"
    assert float(board["plain"]["time_T1_s"]) > 0
    assert float(board["plain"]["vs_fastest_exact"]) > 0
    assert board["crash.sh"]["time_T1_s"] == ""
    # a verdict per T beside the worst; an entry never run has none
    assert [board["plain"][c] for c in ("verdict_T1", "verdict_T2")] == ["exact", "exact"]
    assert [board["crash.sh"][c] for c in ("verdict_T1", "verdict_T2")] == ["failed", "failed"]
    assert board["wall_tolerance"]["verdict_T1"] == "violations"
    assert board["not_executable"]["verdict_T1"] in ("failed", "")


def test_the_first_violation_is_named_with_its_scene(graded):
    _, _, board = graded
    wall = board["wall_tolerance"]
    assert wall["scene"] == "drawn/wall_before_end.in K=1"
    assert "the first at time unit 1, particle 0: wall hit missed" in wall["first_violation"]
    nan = board["nan"]
    assert nan["scene"] == "drawn/corner.in K=1" and "not finite" in nan["first_violation"]
    assert board["crash.sh"]["first_violation"].startswith("crashed: killed by signal 11")
    assert "cannot execute" in board["not_executable"]["first_violation"]
    assert "Permission denied" in board["not_executable"]["first_violation"]
    assert board["plain"]["scene"] == board["plain"]["first_violation"] == ""


def test_a_report_per_submission(graded):
    _, out, _ = graded
    names = ["crash.sh", "nan", "not_executable", "plain", "wall_tolerance"]
    reports = sorted(p.name for p in (out / "reports").iterdir())
    assert reports == sorted([f"{n}.md" for n in names] + [f"{n}.html" for n in names])
    wall = (out / "reports" / "wall_tolerance.md").read_text()
    assert wall.startswith("# wall_tolerance\n\n**violations**, rank ")
    assert "### drawn/wall_before_end.in, T = 1, 2" in wall
    # the violation in full, as the check's report has it
    # not rounded to the step's end (the drawn hit is a few ulps of a step before it)
    assert re.search(r"- time unit 1, particles 0: wall hit missed: the model has a wall hit of "
                     r"particle 0 at t = 0\.99999999999999\d* of the step", wall), wall
    assert "| drawn/dense_random.in | 200 random particles in a box of 400" in wall
    plain = (out / "reports" / "plain.md").read_text()
    assert "| drawn/cradle.in |" in plain and "| exact | exact |" in plain
    assert "## Timing: N=40 L=2000 r=1 S=20 K=1 seed=7" in plain and "###" not in plain
    crash = (out / "reports" / "crash.sh.md").read_text()
    assert "- crashed: killed by signal 11 (Segmentation fault): 26 of 26 runs" in crash


def test_the_sweeps_are_psweeps_own_folders(graded):
    _, out, _ = graded
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    names = [scene["file"].rsplit("/", 1)[-1][:-3] for scene in config["judging"]["scenes"]]
    assert sorted(p.name for p in (out / "judge").iterdir()) == sorted(names)
    for folder in [out / "judge" / n for n in names] + [out / "timing"]:
        assert (folder / "runs.csv").is_file() and (folder / "meta.json").is_file()
    assert (out / "configs" / "timing.json").is_file()


@pytest.mark.parametrize("make, message", [
    (lambda root: root / "nowhere", "does not exist"),
    (lambda root: root / "file", "is not a folder"),
    (lambda root: root / "empty", "holds no submission"),
])
def test_bad_folders_exit_2(tmp_path, make, message):
    (tmp_path / "file").write_text("x")
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / ".gitkeep").write_text("")
    done = grade(make(tmp_path), "--out", tmp_path / "out")
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


def test_bad_configs_and_names_exit_2(tmp_path):
    folder = tmp_path / "submissions"
    folder.mkdir()
    shutil.copy(SUBMISSIONS["plain"], folder / "brute")
    done = grade(folder, "--out", tmp_path / "out", "--config", quick_config(tmp_path))
    assert done.returncode == 2
    assert 'grade: error: the submission brute: shadows psim\'s engine "brute"' in done.stderr
    assert not (tmp_path / "out" / "judge").exists()
    config = tmp_path / "bad.json"
    config.write_text(json.dumps({"judging": {"scenes": [{"file": "scenes/nope.in"}]},
                                  "timing": {"scene": {}}}))
    done = grade(folder, "--out", tmp_path / "out2", "--config", config)
    assert done.returncode == 2 and "judging.scenes[0].file: scenes/nope.in not found" in done.stderr
    config.write_text(json.dumps({"judging": {"scenes": [], "T": [1]}, "timing": {"scene": {}}}))
    done = grade(folder, "--out", tmp_path / "out2", "--config", config)
    assert done.returncode == 2 and "judging.scenes: expected a non-empty list" in done.stderr
    # a scene's verdicts are the board's column of its name: not one the board has already
    shutil.copy(ROOT / "scenes" / "corner.in", tmp_path / "timing.in")
    config.write_text(json.dumps({"judging": {"scenes": [{"file": str(tmp_path / "timing.in")}]},
                                  "timing": {"scene": {}}}))
    done = grade(folder, "--out", tmp_path / "out2", "--config", config)
    assert done.returncode == 2 and "a scene named timing, a column of the scoreboard" in done.stderr
    shutil.copy(ROOT / "scenes" / "corner.in", tmp_path / "verdict_T2.in")  # a verdict per T's
    scene = str(tmp_path / "verdict_T2.in")
    config.write_text(json.dumps({"judging": {"scenes": [{"file": scene}]},
                                  "timing": {"scene": {}}}))
    done = grade(folder, "--out", tmp_path / "out2", "--config", config)
    assert done.returncode == 2 and "a scene named verdict_T2, a column" in done.stderr


def test_gradescope_results_and_grades_csv(graded):
    _, out, _ = graded
    results = {p.parent.name: json.loads(p.read_text())
               for p in (out / "gradescope").glob("*/results.json")}
    assert set(results) == {"plain", "wall_tolerance", "nan", "crash.sh", "not_executable"}
    for result in results.values():  # Gradescope's autograder fields, and nothing it rejects
        assert set(result) == {"score", "tests", "leaderboard"}
        for test in result["tests"]:
            assert set(test) == {"name", "score", "max_score", "output", "status"}
            assert test["status"] in ("passed", "failed") and 0 <= test["score"] <= test["max_score"]
        for entry in result["leaderboard"]:
            assert set(entry) == {"name", "value", "order"} and entry["order"] in ("asc", "desc")
        assert result["score"] == pytest.approx(sum(t["score"] for t in result["tests"]))
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    scenes = len(config["judging"]["scenes"]) + 0
    plain = results["plain"]
    judging = [t for t in plain["tests"] if t["name"].startswith("judging: ")]
    speed = [t for t in plain["tests"] if t["name"].startswith("speed: ")]
    assert len(judging) == scenes and all(t["status"] == "passed" for t in judging)
    assert sum(t["max_score"] for t in judging) == pytest.approx(70)
    # against the lab's plain program; brute and auto: the stretch
    assert [t["name"] for t in speed] == ["speed: T = 1 against plain_allpairs",
                                          "speed: T = 2 against plain_allpairs"]
    assert sum(t["max_score"] for t in plain["tests"]) == pytest.approx(100)
    # The points are the curve's share at the times the output shows (one run each: the times
    # themselves are noise, so no bound on them; at equal times, about half the points).
    mine, theirs = map(float, re.match(r"([\d.e+-]+) s against plain_allpairs's ([\d.e+-]+) s",
                                       speed[0]["output"]).groups())
    assert speed[0]["score"] == pytest.approx(15 * SpeedCurve().time_share(mine / theirs),
                                              abs=0.01), speed
    assert 0.45 < SpeedCurve().time_share(1.0) < 0.55
    assert "its own speed-up over T = 1" in speed[1]["output"], speed
    assert 70 <= plain["score"] <= 100 and [e["name"] for e in plain["leaderboard"]] == [
        "best time (s)", "speed-up against plain_allpairs at T = 1",
        "against brute, the stretch: its best time / yours",
        "against auto, the stretch: its best time / yours"]
    wall = results["wall_tolerance"]
    near = next(t for t in wall["tests"] if t["name"] == "judging: drawn/wall_before_end.in K=1")
    assert near["score"] == 0 and "wall hit missed" in near["output"]
    # Its hit at exactly t = 1, taken at the start of the next step, is a reading the
    # specification allows (docs/model.md): full marks on corner.in.
    corner = next(t for t in wall["tests"] if t["name"] == "judging: drawn/corner.in K=1")
    assert corner["score"] == corner["max_score"] and corner["status"] == "passed", corner
    assert all(t["score"] == 0 for t in wall["tests"] if t["name"].startswith("speed: "))
    assert wall["leaderboard"] == [] and results["crash.sh"]["score"] == 0
    with open(out / "grades.csv", newline="") as f:
        grades = list(csv.DictReader(f))
    assert grades[0]["name"] == "plain"
    assert {g["name"] for g in grades} == set(results)
    assert float(grades[0]["judging_score"]) == pytest.approx(70)
    # No score prints as -0.0 (the speed score was once a difference of rounded sums).
    assert not any(v.startswith("-0") for g in grades for v in g.values()), grades


def test_a_required_reading_reaches_every_sweep_and_a_bad_one_is_refused(tmp_path):
    from analysis.common.load import InputError
    from analysis.grade.plan import judging_config, read_config, timing_config
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    path = tmp_path / "g.json"
    path.write_text(json.dumps({**config, "reading": "whole-motion",
                                "overlap_reading": "approaching"}))
    grade_config = read_config(path)
    programs = {"p": BUILD / "plain_allpairs"}
    lab = {"plain_allpairs": BUILD / "plain_allpairs"}
    judging = judging_config(grade_config, grade_config.scenes[0], programs)
    assert (judging["reading"], judging["overlap_reading"]) == ("whole-motion", "approaching")
    assert timing_config(grade_config, programs, 1, lab)["reading"] == "whole-motion"
    plain = timing_config(read_config(ROOT / "configs" / "grade.json"), programs, 1, lab)
    assert "reading" not in plain and "overlap_reading" not in plain
    path.write_text(json.dumps({**config, "reading": "diagonal"}))
    with pytest.raises(InputError, match="reading: expected one of per-coordinate, "
                                         "whole-motion"):
        read_config(path)
    path.write_text(json.dumps({**config, "overlap_reading": "never"}))
    with pytest.raises(InputError, match="overlap_reading: expected one of approaching, always"):
        read_config(path)


def test_the_board_has_a_column_per_scene_and_the_page_says_each(graded):
    _, out, board = graded
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    scenes = [s["file"].rsplit("/", 1)[-1][:-3] for s in config["judging"]["scenes"]]
    columns = list(next(iter(board.values())))
    assert columns[columns.index("first_violation") + 1:][:len(scenes) + 1] == scenes + ["timing"]
    wall = board["wall_tolerance"]
    assert wall["wall_before_end"] == "violations" and wall["cradle"] == "exact"
    assert wall["corner"] == "ambiguous"  # its hit at t = 1 taken in the next step: a reading
    assert board["crash.sh"]["corner"] == "failed" and board["crash.sh"]["timing"] == ""
    assert board["brute"]["corner"] == "" and board["brute"]["timing"] == "exact"
    with open(out / "grades.csv", newline="") as f:
        scores = {g["name"]: g["score"] for g in csv.DictReader(f)}
    assert {n: r["score"] for n, r in board.items() if r["kind"] == "program"} == scores
    page = (out / "scoreboard.md").read_text()
    assert page.startswith("# Scoreboard: 5 submissions of ")
    assert "| [report](reports/wall_tolerance.html) |" in page
    for column in columns:
        assert f"\n- `{column}`: " in page, column
    assert "- `corner`: the verdict on drawn/corner.in (the worst over its T" in page
    html = (out / "scoreboard.html").read_text()
    assert '<a href="reports/wall_tolerance.html">report</a>' in html
    assert (out / "reports" / "wall_tolerance.html").is_file()


def test_the_reports_name_outputs_as_the_student_knows_them(graded):
    _, out, _ = graded
    for report in (out / "reports").glob("*.md"):
        text = report.read_text()
        assert str(out) not in text and ".out:" not in text, report.name
    score = json.loads((out / "gradescope" / "wall_tolerance" / "results.json").read_text())
    wall = (out / "reports" / "wall_tolerance.md").read_text()
    assert f"{score['score']:.3g} of 100 points" in wall
    row = next((line for line in wall.splitlines()
                if line.startswith("| judging: drawn/wall_before_end.in K=1 |")), None)
    assert row is not None, wall
    # The count is the drawn scene's (a draw can add a later miss), and so is the reading the miss
    # breaks (a drawn vertical velocity can part the two): the row's shape is the point.
    assert re.match(r"\| judging: drawn/wall_before_end\.in K=1 \| 0 \| 5\.38 \| violations: "
                    r"(either|per-coordinate|whole-motion) reading, overlap either: "
                    r"\d+ violations?; the first at time unit 1, "
                    r"particle 0: wall hit missed", row), wall


@pytest.fixture(scope="module")
def garbled(tmp_path_factory):
    """A submission right in print mode and garbage when timed (perf mode), unconfined (it runs
    plain_allpairs, which the sandbox would not show it), on two judging scenes."""
    root = tmp_path_factory.mktemp("garbled")
    folder = root / "submissions"
    folder.mkdir()
    garbage = folder / "garbled"
    garbage.write_text(f"""#!/bin/sh
input=$(cat)
if [ "$(printf '%s\\n' "$input" | sed -n 5p)" = perf ]; then echo 'not a state'; exit 0; fi
printf '%s\\n' "$input" | exec {BUILD / 'plain_allpairs'}
""")
    garbage.chmod(0o755)
    config = json.loads(quick_config(root).read_text())
    config["judging"]["scenes"] = [s for s in config["judging"]["scenes"]
                                   if s["file"] in ("scenes/corner.in", "scenes/wall_beats_pair.in")]
    path = root / "garbled.json"
    path.write_text(json.dumps(config))
    out = root / "out"
    done = grade(folder, "--out", out, "--config", path, "--unconfined")
    assert done.returncode == 0, done.stderr
    with open(out / "scoreboard.csv", newline="") as f:
        board = {row["name"]: row for row in csv.DictReader(f)}
    return out, board


def test_a_malformed_timed_run_hides_no_scene(garbled):
    _, board = garbled
    row = board["garbled"]
    assert row["verdict"] == "malformed" and row["scene"].startswith("N=40 L=2000")
    assert (row["corner"], row["wall_beats_pair"], row["timing"]) == \
        ("exact", "exact", "malformed")
    assert row["first_violation"] == ("timed run's final state: your output for the timing "
                                      "scene, line 1: expected 6 fields `0 0 x y vx vy`, got 3")


def test_the_report_tells_the_timed_and_the_judging_run_together(garbled):
    out, _ = garbled
    report = (out / "reports" / "garbled.md").read_text()
    # its judging run was run and judged, though its timed run was malformed
    assert "| 1 | 1 | 1 ok |" in report
    for t in (1, 2):
        row = next(line for line in report.splitlines() if line.startswith(f"| {t} | 1 | 1 ok"))
        assert row.endswith("| malformed | exact | malformed |"), row
    assert report.index("### T = 1: malformed") < report.index("### T = 2: malformed")
    story = report[report.index("### T = 1: malformed"):report.index("### T = 2")]
    assert ("The timed run (perf mode, its final state):\n\nmalformed: line 1: the output does "
            "not have the 2019 format\n\nyour output for the timing scene, line 1: expected 6 "
            "fields `0 0 x y vx vy`, got 3") in story
    assert ("The judging run (print mode, every step):\n\nexact: identical to the reference at "
            "every printed time unit") in story
    assert str(out) not in report and ".out:" not in report
    result = json.loads((out / "gradescope" / "garbled" / "results.json").read_text())
    speed = [t for t in result["tests"] if t["name"].startswith("speed: ")]
    assert all("malformed on N=40 L=2000" in t["output"] for t in speed), speed


@pytest.mark.parametrize("change, message", [
    (lambda c: c["timing"].update(engines=["plain_allpairs", "octree"]),
     'timing.engines[1]: unknown engine "octree" (psim offers: auto, brute, '),
    (lambda c: c["timing"].update(stretch=["auto", "nope"]),
     'timing.stretch[1]: unknown engine "nope"'),
    (lambda c: c["judging"].update(T=[1, 0]), "judging.T[1]: expected a positive integer, got 0"),
    (lambda c: c["timing"].update(T=[0]), "timing.T[0]: expected a positive integer, got 0"),
    (lambda c: c["judging"].update(timeout_s=-1), "judging.timeout_s: expected a positive number"),
    (lambda c: c["timing"].update(timeout_s=0), "timing.timeout_s: expected a positive number"),
    (lambda c: c["timing"].update(repetitions=0),
     "timing.repetitions: expected a positive integer, got 0"),
    (lambda c: c["timing"].update(warmup=-1), "timing.warmup: expected a non-negative integer"),
    (lambda c: c["timing"]["scene"].update(Nx=3), "timing.scene.Nx: unknown parameter"),
    (lambda c: c["timing"]["scene"].update(N=100000001),
     "timing.scene.N: must be between 1 and 100000000"),
    (lambda c: c.update(pin="tight"), 'pin: expected one of "close", "spread", "none"'),
    (lambda c: c["timing"].update(curve={"full_at": 0.5, "zero_at": 0.4}),
     "timing.curve.zero_at: expected more than full_at (0.5), got 0.4"),
    (lambda c: c["timing"].update(curve={"full_at": "fast"}),
     'timing.curve.full_at: expected a share of the reference\'s time > 0 (0.25: full points at '
     '4 times its speed), got "fast"'),
    (lambda c: c["timing"].update(curve={"speedup_full_at": 1.5}),
     "timing.curve.speedup_full_at: expected a parallel efficiency > 0 and <= 1, got 1.5"),
    (lambda c: c["timing"].update(curve={"steep": 1}), "timing.curve.steep: unknown key"),
    (lambda c: c["timing"].update(quiet={"busy_runs": "ignore"}),
     'timing.quiet.busy_runs: expected one of exclude, count, got "ignore"'),
    (lambda c: c["timing"].update(quiet={"wait_s": -1}),
     "timing.quiet.wait_s: expected seconds from 0 to 3600"),
    (lambda c: c["judging"]["scenes"][2].update(family="nope"),
     'judging.scenes[2].family: unknown family "nope"'),
    (lambda c: c["judging"].update(seed=-3), "judging.seed: expected an integer from 0 to 2^64"),
])
def test_a_bad_grade_config_is_refused_whole_before_the_first_run(tmp_path, change, message):
    folder = tmp_path / "submissions"
    folder.mkdir()
    shutil.copy(SUBMISSIONS["plain"], folder / "alice")
    path = quick_config(tmp_path)
    config = json.loads(path.read_text())
    change(config)
    path.write_text(json.dumps(config))
    done = grade(folder, "--out", tmp_path / "out", "--config", path)
    assert done.returncode == 2, done.stderr
    assert f"grade: error: {path}: {message}" in done.stderr
    assert not (tmp_path / "out" / "judge").exists() and "configs/" not in done.stderr


def test_an_engine_this_build_cannot_run_is_refused_with_what_to_build(tmp_path):
    declared = json.loads(subprocess.run([str(BUILD / "psim"), "--describe"], check=True,
                                         capture_output=True, text=True).stdout)
    why = {e["name"]: e.get("unavailable", "") for e in declared["engines"]}.get("gpu")
    if not why:
        pytest.skip("this build of psim runs gpu")
    folder = tmp_path / "submissions"
    folder.mkdir()
    shutil.copy(SUBMISSIONS["plain"], folder / "alice")
    path = quick_config(tmp_path)
    config = json.loads(path.read_text())
    config["timing"]["stretch"] = ["gpu"]
    path.write_text(json.dumps(config))
    done = grade(folder, "--out", tmp_path / "out", "--config", path)
    assert done.returncode == 2
    assert (f'{path}: timing.stretch[0]: engine "gpu" cannot run in this build of psim: {why}'
            in done.stderr)
    assert not (tmp_path / "out" / "judge").exists()


def test_the_grading_says_its_estimate_and_each_stage(graded):
    done, _, _ = graded
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    stages = len(config["judging"]["scenes"]) + 1
    assert f"then the timing: {stages} sweeps, about " in done.stderr
    assert f"grade: [1/{stages}] judging on drawn/corner.in, " in done.stderr
    assert f"grade: [{stages}/{stages}] timing, " in done.stderr
    assert "grade: the sweeps took " in done.stderr and "(estimated " in done.stderr
    # the timing, once judged: each submission from its own judging runs, the slowest named
    said = re.search(r"grade: the timing, about .*: the lab's references .* \(the cost model's "
                     r"estimate\), the submissions from their own judging runs .* \(the "
                     r"slowest: (.*)\)\n", done.stderr)
    assert said, done.stderr
    assert {part.split()[0] for part in said.group(1).split(", ")} == {"plain", "wall_tolerance",
                                                                      "nan"}
    assert done.stderr.index("grade: the timing, about") < done.stderr.index(
        f"grade: [{stages}/{stages}] timing")
    assert "(estimated " in done.stderr.split("the timing ")[-1]


def test_a_submission_named_like_the_labs_program_is_the_students(tmp_path):
    from analysis.grade.plan import find_submissions
    for name in ("plain_allpairs", "plain_allpairs-2", "plain_allpairs.again", "bob"):
        (tmp_path / name).write_text("#!/bin/sh\n")
    subs = {s.name: s for s in find_submissions(tmp_path)}
    # psweep's name for it is not the lab's program's, and it is shown as it is named
    assert subs["plain_allpairs"].program == "plain_allpairs-3"
    assert subs["plain_allpairs"].shown == "plain_allpairs"
    assert subs["plain_allpairs-2"].program == "plain_allpairs-2"
    # nor the name its runs again are timed by (plan.LAB_AGAIN)
    assert subs["plain_allpairs.again"].program == "plain_allpairs.again-2"
    assert subs["bob"].program == "bob"


def test_the_labs_program_is_timed_twice_as_often_as_a_submission(graded):
    """Its runs as plain_allpairs.again (plan.LAB_AGAIN) are the reference's too: the timing
    sweep has as many of each as of a submission, and the board no row of its own for them."""
    _, out, board = graded
    with open(out / "timing" / "runs.csv", newline="") as f:
        ran = [row["engine"] for row in csv.DictReader(f) if row["status"] == "ok"]
    assert ran.count("plain_allpairs") == ran.count("plain_allpairs.again") == ran.count("plain")
    assert "plain_allpairs.again" not in board and board["plain_allpairs"]["kind"] == "lab"


def test_the_labs_program_must_be_built(tmp_path):
    from analysis.common.load import InputError
    from analysis.grade.plan import lab_programs, read_config
    config = read_config(ROOT / "configs" / "grade.json")
    assert lab_programs(config, BUILD) == {"plain_allpairs": BUILD / "plain_allpairs"}
    with pytest.raises(InputError, match=r"grade.json: timing.engines\[0\]: plain_allpairs, the "
                                         r"lab's program, is not built .*make tools"):
        lab_programs(config, tmp_path)


def test_psweeps_estimate_is_read_in_every_unit():
    from analysis.grade.plan import estimate_s
    table = "engine  configurations  runs  estimate\nplain  2  6  24 s\ntotal  6  18  {}\n"
    for text, seconds in (("0.4 s", 0.4), ("27 s", 27), ("12 min", 720), ("5.1 h", 18360),
                          ("3.2 days", 276480)):
        assert estimate_s(table.format(text)) == pytest.approx(seconds)
    assert estimate_s("no table") == 0
