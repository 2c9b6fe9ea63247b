"""The grade's own rules (analysis/grade: gradescope.py and board.py) on hand-made verdicts and
times, each where a planted bug once survived the whole suite: no speed test pays more than its
points however fast the submission, a submission wrong on the timing scene earns no speed points
and no leaderboard place, and the board ranks every correct submission before a faster wrong one.
Then the board's column per scene, which hides no scene behind the worst, and configs/grade.json's
points, which pay a correct program as fast as the lab's plain one half its speed points. Then the
speed curve (curve.py): a plain program 3 times faster than another earns visibly more, a program
slower at T = 2 than at T = 1 earns no T = 2 points, and busy runs count for nothing.
"""
import json
import math
from pathlib import Path

import pandas as pd
import pytest

from analysis.grade.board import TIMING_COLUMNS, SceneColumn, grade_board
from analysis.grade.gradescope import results_json

ROOT = Path(__file__).resolve().parents[2]
POINTS = {"judging": 70, "speed": 30}
JUDGING = ["scenes/corner.in K=1"]
TIMING = "N=40 L=2000 r=1 S=20 K=1 seed=7"
SCENES = [SceneColumn(JUDGING[0], "corner", "scenes/corner.in", "a corner hit"),
          SceneColumn(TIMING, "timing", "the timing scene", "the timed runs")]


def per_scene(verdicts: dict[str, tuple[str, str]], best_s: dict[str, float]) -> pd.DataFrame:
    """The scene verdicts of each submission: name -> (judging verdict, timing verdict)."""
    rows = []
    for name, (judged, timed) in verdicts.items():
        times = {c: math.nan for c in TIMING_COLUMNS}
        rows.append({"name": name, "kind": "program", "scene": JUDGING[0], "verdict": judged,
                     "first_violation": "", **times})
        rows.append({"name": name, "kind": "program", "scene": TIMING, "verdict": timed,
                     "first_violation": "" if timed == "exact" else "timed run (perf mode)",
                     **times, "best_s": best_s[name], "time_T1_s": best_s[name]})
    return pd.DataFrame(rows)


def timing_runs(times: dict[str, float]) -> pd.DataFrame:
    return pd.DataFrame([{"engine": name, "T": 1.0, "status": "ok", "process_s": s}
                         for name, s in times.items()])


def speed_tests(result):
    return [t for t in result["tests"] if t["name"].startswith("speed: ")]


def test_a_speed_test_pays_at_most_its_points_however_fast():
    scenes = per_scene({"fast": ("exact", "exact")}, {"fast": 0.01})
    result = results_json("fast", scenes, JUDGING, timing_runs({"brute": 1.0, "fast": 0.01}),
                          ["brute"], POINTS)
    (speed,) = speed_tests(result)
    assert speed["max_score"] == pytest.approx(30) and speed["score"] == pytest.approx(30)
    assert "100x its speed" in speed["output"] and speed["status"] == "passed"
    assert result["score"] == pytest.approx(100)


def test_wrong_on_the_timing_scene_earns_no_speed_points_and_no_leaderboard_place():
    # Right on every judging scene, but its timed run is not what it prints in print mode.
    scenes = per_scene({"idler": ("exact", "violations")}, {"idler": 0.01})
    result = results_json("idler", scenes, JUDGING, timing_runs({"brute": 1.0, "idler": 0.01}),
                          ["brute"], POINTS)
    (speed,) = speed_tests(result)
    assert speed["score"] == 0 and f"violations on {TIMING}" in speed["output"]
    assert result["leaderboard"] == []
    assert result["score"] == pytest.approx(70)


def test_the_board_ranks_every_correct_submission_before_a_faster_wrong_one():
    scenes = per_scene({"wrong": ("exact", "violations"), "slow": ("exact", "exact"),
                        "fast": ("consistent", "exact")},
                       {"wrong": 0.001, "slow": 2.0, "fast": 1.0})
    board = grade_board(scenes, SCENES, {})
    assert list(board["name"]) == ["slow", "fast", "wrong"]
    assert list(board["rank"]) == [1, 2, 3]
    assert board.set_index("name").loc["wrong", "scene"] == TIMING


def test_the_board_has_a_verdict_per_scene_beside_the_worst():
    # Malformed when timed: the worst, and still what the judging scene found.
    scenes = per_scene({"garbled": ("exact", "malformed"), "racy": ("violations", "exact")},
                       {"garbled": 0.5, "racy": 0.5})
    board = grade_board(scenes, SCENES, {"garbled": 70.0, "racy": 30.0}).set_index("name")
    assert list(board.columns[:9]) == ["rank", "kind", "score", "verdict", "scene",
                                       "first_violation", "corner", "timing", "time_T1_s"]
    assert board.loc["garbled", ["verdict", "corner", "timing"]].tolist() == \
        ["malformed", "exact", "malformed"]
    assert board.loc["racy", ["verdict", "corner", "timing"]].tolist() == \
        ["violations", "violations", "exact"]
    assert board.loc["garbled", "score"] == 70 and board.loc["racy", "report"] == \
        "reports/racy.html"


def test_the_default_config_pays_a_correct_program_as_fast_as_the_labs_plain_one_half():
    # The speed points are against the lab's plain_allpairs alone; brute and auto, 30 and 100
    # times faster here, are the stretch: shown on the leaderboard, worth no points. On the
    # config's curve, the reference's own time earns half a test's points.
    from analysis.grade.plan import read_config
    config = read_config(ROOT / "configs" / "grade.json")
    timing = config.timing
    assert timing["engines"] == ["plain_allpairs"] and timing["stretch"] == ["brute", "auto"]
    assert config.curve.time_share(1.0) == pytest.approx(0.5)
    scenes = per_scene({"mine": ("exact", "exact")}, {"mine": 3.0})
    result = results_json("mine", scenes, JUDGING,
                          timing_runs({"plain_allpairs": 3.0, "brute": 0.1, "auto": 0.03,
                                       "mine": 3.0}),
                          timing["engines"], config.points, timing["stretch"], config.curve,
                          config.quiet)
    assert [t["name"] for t in speed_tests(result)] == ["speed: T = 1 against plain_allpairs"]
    assert result["score"] == pytest.approx(config.points["judging"]
                                            + config.points["speed"] / 2)
    assert result["leaderboard"][1] == {"name": "speed-up against plain_allpairs at T = 1",
                                        "value": 1.0, "order": "desc"}
    assert result["leaderboard"][-1] == {"name": "against auto, the stretch: its best time / "
                                                 "yours", "value": 0.01, "order": "desc"}


def test_the_reference_is_its_least_time_over_its_runs_again_too():
    # Every point is a time over the reference's: the lab's program is timed again under a
    # second name (plan.LAB_AGAIN), and a grading's runs name those as the program's
    # (as_lab_runs): its least time is over both names' runs, here the second name's.
    from analysis.grade.plan import as_lab_runs
    runs = pd.DataFrame([{"engine": name, "T": 1.0, "status": "ok", "process_s": s}
                         for name, s in [("plain_allpairs", 1.5), ("plain_allpairs", 1.6),
                                         ("plain_allpairs.again", 1.0),
                                         ("plain_allpairs.again", 1.7), ("mine", 1.0)]])
    scenes = per_scene({"mine": ("exact", "exact")}, {"mine": 1.0})
    result = results_json("mine", scenes, JUDGING, as_lab_runs(runs), ["plain_allpairs"], POINTS)
    (speed,) = speed_tests(result)
    assert "1 s against plain_allpairs's 1 s" in speed["output"]
    assert speed["score"] == pytest.approx(POINTS["speed"] / 2)


def timing_runs_at(times: dict[tuple[str, float], float], busy=()) -> pd.DataFrame:
    """Timed runs: (name, T) -> its time; `busy`: the (name, T) whose run psweep started on a
    busier machine than the sweep's start (busy_tasks > 0)."""
    return pd.DataFrame([{"engine": name, "T": t, "status": "ok", "process_s": s,
                          "busy_tasks": 2 if (name, t) in busy else 0}
                         for (name, t), s in times.items()])


def speed_score(name: str, times: dict, **rules) -> float:
    scenes = per_scene({name: ("exact", "exact")}, {name: min(times.values())})
    result = results_json(name, scenes, JUDGING, timing_runs_at(times), ["plain_allpairs"],
                          POINTS, **rules)
    return sum(t["score"] for t in speed_tests(result))


def test_a_plain_program_3_times_faster_than_another_earns_visibly_more():
    # Both plain (one thread) and both faster than the lab's reference: the old
    # min(1, reference / time) paid the two alike, in full.
    reference = {("plain_allpairs", 1.0): 3.0}
    fast = speed_score("fast", {**reference, ("fast", 1.0): 0.5})
    slow = speed_score("slow", {**reference, ("slow", 1.0): 1.5})
    slower = speed_score("slower", {**reference, ("slower", 1.0): 4.5})
    assert fast - slow > 0.2 * 30 and slow - slower > 0.2 * 30, (fast, slow, slower)
    # as fast as the reference: half the points by default; at 4 times its speed, all
    assert speed_score("same", {**reference, ("same", 1.0): 3.0}) == pytest.approx(15)
    assert speed_score("quick", {**reference, ("quick", 1.0): 0.75}) == pytest.approx(30)


def test_a_program_slower_at_T2_than_at_T1_earns_no_T2_points():
    # Fast at T = 1, and at T = 2 faster than the reference there, but slower than itself at
    # T = 1: its threads idle or fight. The old rule paid T = 2 by its time alone.
    times = {("plain_allpairs", 1.0): 3.0, ("plain_allpairs", 2.0): 3.0,
             ("idler", 1.0): 1.0, ("idler", 2.0): 1.4}
    scenes = per_scene({"idler": ("exact", "exact")}, {"idler": 1.0})
    result = results_json("idler", scenes, JUDGING, timing_runs_at(times), ["plain_allpairs"],
                          POINTS)
    t1, t2 = speed_tests(result)
    assert t1["name"] == "speed: T = 1 against plain_allpairs" and t1["score"] > 0
    assert t2["score"] == 0 and t2["status"] == "failed", t2
    assert "its own speed-up over T = 1 0.714" in t2["output"], t2["output"]
    # the same T = 2 time with a real speed-up earns its points
    times[("idler", 1.0)] = 2.5
    result = results_json("idler", scenes, JUDGING, timing_runs_at(times), ["plain_allpairs"],
                          POINTS)
    assert speed_tests(result)[1]["score"] > 0.5 * 15


def test_busy_runs_are_excluded_from_the_points_and_said():
    times = {("plain_allpairs", 1.0): 3.0, ("lucky", 1.0): 0.5}
    scenes = per_scene({"lucky": ("exact", "exact")}, {"lucky": 0.5})
    runs = pd.concat([timing_runs_at(times, busy={("lucky", 1.0)}),
                      timing_runs_at({("lucky", 1.0): 3.0})])
    (speed,) = speed_tests(results_json("lucky", scenes, JUDGING, runs, ["plain_allpairs"],
                                        POINTS))
    assert speed["output"].startswith("3 s against plain_allpairs's 3 s") and \
        speed["output"].endswith("(1 busy run excluded)"), speed["output"]
    assert speed["score"] == pytest.approx(15)
    # every run busy: none counts
    (speed,) = speed_tests(results_json("lucky", scenes, JUDGING,
                                        timing_runs_at(times, busy={("lucky", 1.0)}),
                                        ["plain_allpairs"], POINTS))
    assert speed["score"] == 0 and speed["output"] == "no counted timed run (1 busy run excluded)"
    # a config that counts them
    from analysis.grade.curve import Quiet
    (speed,) = speed_tests(results_json("lucky", scenes, JUDGING, runs, ["plain_allpairs"],
                                        POINTS, quiet=Quiet(busy_runs="count")))
    assert speed["score"] == pytest.approx(30)


def test_the_board_has_a_verdict_per_T_so_a_T2_failure_hides_nothing_of_T1():
    # Exact on every scene at T = 1, failed at T = 2 (a thread that cannot start): the worst
    # over T alone read "failed" and hid every judged run of T = 1.
    t1 = per_scene({"racy": ("exact", "exact"), "plain": ("exact", "exact")},
                   {"racy": 1.0, "plain": 2.0})
    t2 = per_scene({"racy": ("failed", "exact"), "plain": ("exact", "exact")},
                   {"racy": 1.0, "plain": 2.0})
    board = grade_board(t2, SCENES, {}, {1.0: t1, 2.0: t2}).set_index("name")
    assert list(board.columns[:6]) == ["rank", "kind", "score", "verdict", "verdict_T1",
                                       "verdict_T2"]
    assert board.loc["racy", ["verdict", "verdict_T1", "verdict_T2"]].tolist() == \
        ["failed", "exact", "failed"]
    assert board.loc["plain", ["verdict_T1", "verdict_T2"]].tolist() == ["exact", "exact"]


def judging_runs(times: dict[str, tuple[float, float]]) -> pd.DataFrame:
    """Judging runs of each program: name -> (its time on a 2-particle, 4-step scene, on a
    200-particle, 300-step one), at T = 1 and 2 alike."""
    rows = []
    for name, (small, large) in times.items():
        for t in (1, 2):
            rows += [{"engine": name, "T": t, "N": 2, "S": 4, "slow_factor": 1, "status": "ok",
                      "process_s": small},
                     {"engine": name, "T": t, "N": 200, "S": 300, "slow_factor": 1,
                      "status": "ok", "process_s": large}]
    return pd.DataFrame(rows)


def test_each_submission_is_estimated_from_its_own_judging_runs():
    # A program 10 times slower than another on the judging scenes is estimated 10 times as
    # long on the timing scene (N = 1000, S = 1000: 83 times the large scene's all-pairs work),
    # not priced as the lab's plain program; each run capped at the timing's timeout.
    from analysis.grade.estimate import timing_estimates_s
    runs = judging_runs({"quick": (0.01, 0.03), "slow": (0.01, 0.21), "broken": (0.01, 0.01)})
    runs.loc[runs["engine"] == "broken", "status"] = "failed"
    scene = {"N": 1000, "S": 1000, "L": 20000, "r": 1}
    est = timing_estimates_s(runs, ["quick", "slow", "broken"], scene, [1, 2], 5, 60)
    assert set(est) == {"quick", "slow"}  # no ok judging run, nothing to estimate it by
    per_run = 0.02 * 1000 ** 3 / (200 ** 2 * 300)
    assert est["quick"] == pytest.approx(2 * 5 * (0.01 + per_run))
    assert est["slow"] == pytest.approx(2 * 5 * (0.01 + 10 * per_run))
    assert timing_estimates_s(runs, ["slow"], scene, [1, 2], 5, 10)["slow"] == pytest.approx(100)
