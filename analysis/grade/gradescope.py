"""Grades in the format course tools read: per submission, `results.json` in Gradescope's
autograder format (docs/programs.md, "Grades for Gradescope"), and one `grades.csv` for the
folder.

  a test per judging scene   full marks for exact, consistent or ambiguous (the model followed
                             within rounding, or a hit at exactly the step's end taken in the
                             next step) at every T; zero for violations, malformed or a
                             failed run, with the first violation or the failure as its output
  a test per reference and T the speed against the lab's reference at that T on the timing
                             scene (timing.engines: plain_allpairs by default, the model written
                             the plain way with care; psim's engines may be named too), on the
                             config's curve (curve.py: full points at a quarter of its time by
                             default, none at 4 times it, logarithmic between); at a T above the
                             smallest, times the share of the program's own speed-up over the
                             smallest T (none at 1 or less: idle threads earn nothing); only the
                             runs psweep started on a quiet machine count, unless timing.quiet
                             says otherwise; zero when the submission is wrong anywhere, since a
                             wrong program's speed means nothing
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
from analysis.grade.curve import Quiet, SpeedCurve

PASSING = {"exact", "consistent", "ambiguous"}
DEFAULT_POINTS = {"judging": 70, "speed": 30}


def _counted(timing: pd.DataFrame, quiet: Quiet) -> tuple[pd.DataFrame, dict]:
    """The ok timed runs that count for points, and (engine or program, T) -> how many ok runs
    were excluded as busy: started while more tasks ran than when the sweep began (psweep's
    busy_tasks; results from before that column count whole)."""
    ok = timing[(timing["status"] == "ok") & timing["process_s"].notna()]
    if quiet.busy_runs == "count" or "busy_tasks" not in ok:
        return ok, {}
    busy = ok["busy_tasks"].fillna(0) > 0
    excluded = {key: len(runs) for key, runs in ok[busy].groupby(["engine", "T"])}
    return ok[~busy], excluded


def _best_times(ok: pd.DataFrame, how: str = "min") -> dict[tuple[str, float], float]:
    """(engine or program, T) -> the least whole-process time of its counted runs (`how`
    "median": their median, what the spread of the points is taken from)."""
    return {(name, t): float(runs["process_s"].agg(how))
            for (name, t), runs in ok.groupby(["engine", "T"])}


def window(timing: pd.DataFrame, name: str) -> pd.DataFrame:
    """The timed runs `name` is scored among: those of the timing sweep it ran in (`results`,
    its folder: on a cluster each is one node's, the references timed there interleaved with
    it), so that its speed is its time over the reference's on the same node in the same
    window, whatever the other nodes are; every run where it was not timed, or where the runs
    name no folder (one timing sweep)."""
    if "results" not in timing:
        return timing
    mine = timing.loc[timing["engine"] == name, "results"]
    return timing[timing["results"] == mine.iloc[0]] if not mine.empty else timing


def beside(timing: pd.DataFrame, name: str, engines: list[str], quiet: Quiet) -> dict:
    """What the scoreboard keeps of a submission's window: the node(s) its timed runs ran on,
    and the first reference's least counted time at the smallest T there (nan without one)."""
    runs = window(timing, name)
    nodes = runs.loc[runs["engine"] == name, "node"].dropna() if "node" in runs else []
    times = _best_times(_counted(runs, quiet)[0])
    threads = sorted(runs["T"].dropna().unique())
    reference = times.get((engines[0], threads[0]), math.nan) if engines and threads else math.nan
    return {"reference_s": reference, "node": ", ".join(sorted(set(map(str, nodes))))}


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


def _busy_note(excluded: dict, name: str, t: float) -> str:
    count = excluded.get((name, t), 0)
    return f" ({count} busy run{'s' * (count != 1)} excluded)" if count else ""


def _speed_share(name: str, engine: str, t: float, base: float, times: dict,
                 curve: SpeedCurve) -> tuple[float, str, bool]:
    """The share of a speed test's points, what to say of it and whether it passed, for a
    submission and a reference that both have a counted time at T = t."""
    mine, theirs = times[(name, t)], times[(engine, t)]
    share = curve.time_share(mine / theirs)
    said = (f"{mine:.4g} s against {engine}'s {theirs:.4g} s: {theirs / mine:.3g}x its speed, "
            f"{share:.0%} of the points by time")
    passed = mine <= theirs
    if t > base:
        own = times.get((name, base))
        if own is None:
            return 0.0, said + f"; no counted run at T = {base:g} to measure its speed-up " \
                               "by, so none", False
        speedup = own / mine
        kept = curve.speedup_share(speedup, t / base)
        share *= kept
        said += (f"; its own speed-up over T = {base:g} {speedup:.3g} (full at "
                 f"{curve.speedup_full_at * t / base:.3g}): {kept:.0%} of them kept")
        passed = passed and speedup > 1
    return share, said, passed


def _speed_tests(name: str, wrong: str, times: dict, medians: dict, excluded: dict,
                 engines: list[str], threads: list[float], points: float,
                 curve: SpeedCurve) -> tuple[list[dict], float]:
    """`wrong`: why the submission is not graded for speed (_wrong), empty when it is; `times`
    and `excluded` as _best_times and _counted give them, `medians` the medians of the same
    runs. Returns the tests and their spread: how far the points move within the repetitions'
    noise, from the submission's least time over the reference's median to its median over the
    reference's least time, which is what two gradings of one program (two nodes, two windows)
    can differ by."""
    pairs = [(e, t) for e in engines for t in threads]
    each = points / len(pairs) if pairs else 0
    tests, spread = [], 0.0
    for engine, t in pairs:
        mine, theirs = times.get((name, t)), times.get((engine, t))
        label = f"speed: T = {t:g} against {engine}"
        if mine is None or theirs is None or wrong:
            why = (f"no counted timed run{_busy_note(excluded, name, t)}" if mine is None else
                   f"{engine} has no counted timed run{_busy_note(excluded, engine, t)}"
                   if theirs is None else wrong)
            tests.append({"name": label, "score": 0, "max_score": each, "output": why,
                          "status": "failed"})
            continue
        share, said, passed = _speed_share(name, engine, t, threads[0], times, curve)
        best = {k: (v if k[0] == name else medians.get(k, v)) for k, v in times.items()}
        worst = {k: (medians.get(k, v) if k[0] == name else v) for k, v in times.items()}
        high = _speed_share(name, engine, t, threads[0], best, curve)[0]
        low = _speed_share(name, engine, t, threads[0], worst, curve)[0]
        spread += each * abs(high - low)
        tests.append({"name": label, "score": each * share, "max_score": each,
                      "output": said + f"; {low:.0%} to {high:.0%} within the repetitions' "
                                       "spread"
                      + _busy_note(excluded, name, t),
                      "status": "passed" if passed else "failed"})
    return tests, spread


def _best(times: dict, name: str) -> float:
    """The least time of a name over every T."""
    return min((v for (n, _), v in times.items() if n == name), default=math.nan)


def results_json(name: str, per_scene: pd.DataFrame, judging_scenes: list[str],
                 timing: pd.DataFrame, engines: list[str], points: dict,
                 stretch: list[str] = (), curve: SpeedCurve = SpeedCurve(),
                 quiet: Quiet = Quiet()) -> dict:
    """One submission's results.json. `per_scene`: the grade's scene verdicts (board.py),
    `timing`: the timing sweep's runs, `engines`: the lab's references its speed points are
    against, `stretch`: those it is shown against on the leaderboard alone; `curve` and
    `quiet`: the grade config's (curve.py). Scored among its window's runs alone (window)."""
    return _graded(name, per_scene, judging_scenes, timing, engines, points, stretch, curve,
                   quiet)[0]


def _graded(name: str, per_scene: pd.DataFrame, judging_scenes: list[str],
            timing: pd.DataFrame, engines: list[str], points: dict, stretch: list[str],
            curve: SpeedCurve, quiet: Quiet) -> tuple[dict, float]:
    """results_json's and the spread of its speed points (_speed_tests)."""
    timing = window(timing, name)
    mine = per_scene[per_scene["name"] == name]
    judging = _judging_tests(mine, judging_scenes, points["judging"])
    wrong = _wrong(mine, judging_scenes)
    counted, excluded = _counted(timing, quiet)
    times = _best_times(counted)
    threads = sorted(timing["T"].dropna().unique())
    speed, spread = _speed_tests(name, wrong, times, _best_times(counted, "median"), excluded,
                                 engines, threads, points["speed"], curve)
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
            "leaderboard": leaderboard}, round(spread, 4)


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
                 points: dict, stretch: list[str], curve: SpeedCurve,
                 quiet: Quiet) -> dict[str, dict]:
    """OUT/gradescope/<program>/results.json per submission and OUT/grades.csv; `programs`:
    psweep's name -> the name shown. Returns each program's results.json."""
    # Folders of an earlier grading would stand for submissions no longer graded.
    shutil.rmtree(out / "gradescope", ignore_errors=True)
    rows, results = [], {}
    for program, shown in programs.items():
        result, spread = _graded(program, per_scene, judging_scenes, timing, engines, points,
                                 stretch, curve, quiet)
        results[program] = result
        folder = out / "gradescope" / program
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "results.json").write_text(json.dumps(result, indent=2) + "\n")
        judging = [t for t in result["tests"] if t["name"].startswith("judging")]
        speed = [t for t in result["tests"] if not t["name"].startswith("judging")]
        board = {e["name"]: e["value"] for e in result["leaderboard"]}
        rows.append({"name": shown, "score": result["score"],
                     "max_score": points_sum(result["tests"], "max_score"),
                     "judging_score": points_sum(judging, "score"),
                     "speed_score": points_sum(speed, "score"), "speed_spread": spread,
                     "best_s": board.get("best time (s)", math.nan),
                     "speedup": board.get(speedup_name(engines[0]), math.nan)
                     if engines else math.nan})
    grades = pd.DataFrame(rows).sort_values("score", ascending=False, kind="stable")
    write_csv(grades, out / "grades.csv")
    return results
