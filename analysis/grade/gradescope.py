"""Grades in the format course tools read: per submission, `results.json` in Gradescope's
autograder format (docs/programs.md, "Grades for Gradescope"), and one `grades.csv` for the
folder.

  a test per judging scene   full marks for exact, consistent or ambiguous (the model followed
                             within rounding, or a hit at exactly the step's end taken in the
                             next step) at every T; zero for violations, malformed or a
                             failed run, with the first violation or the failure as its output
  a test per reference and T the speed against the lab's reference at that T on the timing
                             scene (timing.engines: plain_allpairs by default, the model written
                             the plain way, what a correct straightforward program is; psim's
                             engines may be named too): full marks at its time or
                             faster, else in proportion (engine time / submission time); zero
                             when the submission is wrong anywhere, since a wrong program's speed
                             means nothing
  leaderboard                the best time (lower first), the speed-up against the first
                             reference at T = 1 and, per reference of timing.stretch (brute and
                             auto by default: timed, no points), its best time over the
                             submission's (higher first)

The points are the grade config's `points` ({"judging": 70, "speed": 30} by default), each
shared equally among its tests.
"""
from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pandas as pd

from analysis.common.csv_out import write_csv

PASSING = {"exact", "consistent", "ambiguous"}
DEFAULT_POINTS = {"judging": 70, "speed": 30}


def _best_times(timing: pd.DataFrame) -> dict[tuple[str, float], float]:
    """(engine or program, T) -> the least whole-process time of its ok runs."""
    ok = timing[(timing["status"] == "ok") & timing["process_s"].notna()]
    return {(name, t): float(runs["process_s"].min())
            for (name, t), runs in ok.groupby(["engine", "T"])}


def _judging_tests(mine: pd.DataFrame, scenes: list[str], points: float) -> list[dict]:
    """`mine`: the submission's per-scene rows of the grade's scene verdicts."""
    each = points / len(scenes) if scenes else 0
    tests = []
    for scene in scenes:
        row = mine[mine["scene"] == scene]
        verdict = row.iloc[0]["verdict"] if not row.empty else "failed"
        passed = verdict in PASSING
        first = row.iloc[0]["first_violation"] if not row.empty else "not run"
        output = verdict if passed else f"{verdict}: {first}"
        tests.append({"name": f"judging: {scene}", "score": each if passed else 0,
                      "max_score": each, "output": output,
                      "status": "passed" if passed else "failed"})
    return tests


def _wrong(mine: pd.DataFrame, judging_scenes: list[str]) -> str:
    """Why a submission earns no speed points: every scene it is not judged right on; empty
    when it is right on every one."""
    wrong = mine[~mine["verdict"].isin(PASSING)]
    problems = [f"{row['verdict']} on {row['scene']}" for _, row in wrong.iterrows()]
    problems += [f"not run on {scene}" for scene in judging_scenes
                 if scene not in set(mine["scene"])]
    return ("not graded for speed, a wrong program's speed means nothing: "
            + "; ".join(problems)) if problems else ""


def _speed_tests(name: str, wrong: str, times: dict, engines: list[str],
                 threads: list[float], points: float) -> list[dict]:
    """`wrong`: why the submission is not graded for speed (_wrong), empty when it is."""
    pairs = [(e, t) for e in engines for t in threads]
    each = points / len(pairs) if pairs else 0
    tests = []
    for engine, t in pairs:
        mine, theirs = times.get((name, t)), times.get((engine, t))
        label = f"speed: T = {t:g} against {engine}"
        if mine is None or theirs is None or wrong:
            why = ("no ok timed run" if mine is None else
                   f"{engine} has no ok timed run" if theirs is None else wrong)
            tests.append({"name": label, "score": 0, "max_score": each, "output": why,
                          "status": "failed"})
            continue
        ratio = theirs / mine
        tests.append({"name": label, "score": each * min(1.0, ratio),
                      "max_score": each,
                      "output": f"{mine:.4g} s against {engine}'s {theirs:.4g} s: "
                                f"{ratio:.3g}x its speed",
                      "status": "passed" if ratio >= 1 else "failed"})
    return tests


def _best(times: dict, name: str) -> float:
    """The least time of a name over every T."""
    return min((v for (n, _), v in times.items() if n == name), default=math.nan)


def results_json(name: str, per_scene: pd.DataFrame, judging_scenes: list[str],
                 timing: pd.DataFrame, engines: list[str], points: dict,
                 stretch: list[str] = ()) -> dict:
    """One submission's results.json. `per_scene`: the grade's scene verdicts (board.py),
    `timing`: the timing sweep's runs, `engines`: the lab's references its speed points are
    against, `stretch`: those it is shown against on the leaderboard alone."""
    mine = per_scene[per_scene["name"] == name]
    judging = _judging_tests(mine, judging_scenes, points["judging"])
    wrong = _wrong(mine, judging_scenes)
    times = _best_times(timing)
    threads = sorted(timing["T"].dropna().unique())
    speed = _speed_tests(name, wrong, times, engines, threads, points["speed"])
    tests = judging + speed
    best = _best(times, name)
    leaderboard = []
    if not wrong and not math.isnan(best):
        leaderboard = [{"name": "best time (s)", "value": round(best, 6), "order": "asc"}]
        if engines:
            first = times.get((engines[0], 1.0), math.nan)
            leaderboard.append({"name": speedup_name(engines[0]),
                                "value": round(first / best, 4) if not math.isnan(first) else 0,
                                "order": "desc"})
        leaderboard += [{"name": stretch_name(engine),
                         "value": round(_best(times, engine) / best, 4)
                         if not math.isnan(_best(times, engine)) else 0, "order": "desc"}
                        for engine in stretch]
    return {"score": points_sum(tests, "score"), "tests": tests,
            "leaderboard": leaderboard}


def speedup_name(engine: str) -> str:
    """The leaderboard's entry of the speed-up against the first reference, grades.csv's
    `speedup`."""
    return f"speed-up against {engine} at T = 1"


def stretch_name(engine: str) -> str:
    """A stretch engine's leaderboard entry."""
    return f"against {engine}, the stretch: its best time / yours"


def points_sum(tests: list[dict], key: str) -> float:
    """The tests' points to 4 decimals; + 0.0 makes a rounded -0.0 (a difference of sums that
    cancel) read 0.0, as grades.csv once printed it."""
    return round(sum(t[key] for t in tests), 4) + 0.0


def write_grades(out: Path, programs: dict[str, str], per_scene: pd.DataFrame,
                 judging_scenes: list[str], timing: pd.DataFrame, engines: list[str],
                 points: dict, stretch: list[str]) -> dict[str, dict]:
    """OUT/gradescope/<program>/results.json per submission and OUT/grades.csv; `programs`:
    psweep's name -> the name shown. Returns each program's results.json."""
    # Folders of an earlier grading would stand for submissions no longer graded.
    shutil.rmtree(out / "gradescope", ignore_errors=True)
    rows, results = [], {}
    for program, shown in programs.items():
        result = results[program] = results_json(program, per_scene, judging_scenes, timing,
                                                 engines, points, stretch)
        folder = out / "gradescope" / program
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "results.json").write_text(json.dumps(result, indent=2) + "\n")
        judging = [t for t in result["tests"] if t["name"].startswith("judging")]
        speed = [t for t in result["tests"] if not t["name"].startswith("judging")]
        board = {e["name"]: e["value"] for e in result["leaderboard"]}
        rows.append({"name": shown, "score": result["score"],
                     "max_score": points_sum(result["tests"], "max_score"),
                     "judging_score": points_sum(judging, "score"),
                     "speed_score": points_sum(speed, "score"),
                     "best_s": board.get("best time (s)", math.nan),
                     "speedup": board.get(speedup_name(engines[0]), math.nan)
                     if engines else math.nan})
    grades = pd.DataFrame(rows).sort_values("score", ascending=False, kind="stable")
    write_csv(grades, out / "grades.csv")
    return results
