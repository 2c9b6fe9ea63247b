"""One Markdown report per submission, written for its student: the grade, rank and points, a
table of every scene with the verdict at each T, then a story per scene the check found something
on, its findings in full (from the check's report beside the output,
DIR/outputs/<config_id>.check.json), T ascending. The timing scene's story puts the timed runs'
verdict (their final state, perf mode) beside the judging run's (the same particles in print
mode, step by step: DIR/outputs/<config_id>.judge.check.json) and the verdict the two make
together, which is the one the tables show. Outputs are named as the student knows them: their
output for a scene, and its line (board.in_student_words)."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from analysis.common.markdown import cell, markdown_table
from analysis.grade.board import in_student_words, student_scene
from analysis.scoreboard.board import worst_verdict

SHOWN = 5  # violations and ambiguous time units shown per check; the .check.json has the rest
PASSED = ("exact", "consistent")  # no story to tell


@dataclass
class Grading:
    """What every report of one grading shares."""
    out: Path                  # the grading's folder: files are named from it
    runs: pd.DataFrame         # every sweep's runs with the scene label (board.with_scenes) and
                               # `results`, the folder each row came from
    tests: dict[str, str]      # judging scene as shown (plan.JudgingScene.shown) -> what it
                               # tests, in the config's order
    timing_scene: str          # the timing scene's label
    count: int                 # rows of the board
    results: dict[str, dict]   # program -> its results.json (gradescope.py)
    confined: bool             # run in the sandbox (else --unconfined)
    args: list[str] = field(default_factory=list)  # the grade config's submission.args
    drawn: str = ""            # how the judging scenes were drawn, their seed (cli.drawn_line)


def _words(row):
    """in_student_words for the outputs of a run."""
    return lambda text: in_student_words(str(text), row["results"], student_scene(row))


def _check_report(row, judging_run: bool = False) -> tuple[dict | None, Path]:
    """The psim check report psweep kept for the run of this row (the timed run's, or its
    judging run's), and its file."""
    name = f"{row['config_id']}{'.judge' if judging_run else ''}.check.json"
    path = Path(row["results"]) / "outputs" / name
    try:
        return json.loads(path.read_text()), path
    except (OSError, json.JSONDecodeError):
        return None, path


def _listed(title: str, items: list[dict], total: int, source: str, words) -> list[str]:
    lines = [f"{title} (the first {min(len(items), SHOWN)} of {total}):", ""]
    for item in items[:SHOWN]:
        particles = ", ".join(str(p) for p in item.get("particles", []))
        kind = f"{item['kind']}: " if "kind" in item else ""
        # The check gives no size where there is none to give (a value that is not finite).
        off = item.get("difference")
        size = f" (off by {cell(float(off))})" if isinstance(off, (int, float)) else ""
        lines.append(f"- time unit {item.get('step')}, particles {particles}: {kind}"
                     f"{words(item.get('detail', ''))}{size}")
    if total > SHOWN:
        lines.append(f"- ... the rest in the grading's `{source}`")
    return lines + [""]


def _findings(row, grading: Grading, judging_run: bool = False) -> list[str]:
    """What the check found for one output of a run, in full; its verdict and detail as runs.csv
    has them where the report is missing."""
    words = _words(row)
    report, path = _check_report(row, judging_run)
    if report is None:
        return [f"{row['check']}: {words(row['check_detail'])}", ""]
    source = path.relative_to(grading.out) if path.is_relative_to(grading.out) else path
    lines = [f"{report.get('verdict')}: {words(report.get('summary', ''))}", ""]
    malformed = report.get("malformed")
    if isinstance(malformed, dict):
        lines += [words(malformed.get("message", "")), ""]
    kinds = report.get("kinds") or {}
    if kinds:
        lines += ["Violations per kind: " + ", ".join(f"{k}: {n}" for k, n in kinds.items()), ""]
    violations = report.get("violations") or []
    if violations:
        lines += _listed("Violations", violations, int(report.get("violation_count",
                                                                 len(violations))), source, words)
    ambiguous = report.get("ambiguous") or []
    if ambiguous:
        lines += _listed("Ambiguous (the print rounding, or a contact at the step's end)",
                         ambiguous, len(ambiguous), source, words)
    return lines


def _verdict_at(runs: pd.DataFrame) -> str:
    """The verdict of one scene at one T: a run's status where one was not ok, else the worst
    check of its runs (the timing scene's repetitions, each compared with the judged one)."""
    bad = runs[runs["status"] != "ok"]
    return bad.iloc[0]["status"] if not bad.empty else worst_verdict(runs)[0]


def _scene_row(scene: str, tests: str, runs: pd.DataFrame) -> dict:
    row = {"scene": scene, "tests": tests}
    row.update({f"T={cell(t)}": _verdict_at(at) for t, at in runs.groupby("T")})
    row["first step"] = runs["check_first_step"].min()
    return row


def _scene_table(judged: pd.DataFrame, timed: pd.DataFrame, grading: Grading) -> pd.DataFrame:
    """A row per scene, in the config's order, the timing scene last: the verdict at each T
    and the first time unit any T broke the model."""
    rows = [_scene_row(scene, grading.tests.get(scene, ""), runs)
            for scene, runs in judged.groupby("scene_file", sort=False)]
    timing = f"the timing scene ({grading.timing_scene})"
    if timed.empty:
        rows.append({"scene": timing, "tests": "not timed: no judging run of it ended ok"})
    else:
        rows.append(_scene_row(timing, "your timed runs (perf mode: their final state) and a "
                                       "judging run of the same particles (print mode: every "
                                       "step); its section below", timed))
    table = pd.DataFrame(rows)
    threads = sorted((c for c in table.columns if c.startswith("T=")),
                     key=lambda c: float(c[2:]))
    return table[["scene", "tests", *threads, "first step"]]


def _failures(runs: pd.DataFrame) -> list[str]:
    """Runs that were not ok, one line per message: a crash is the same crash on every scene."""
    bad = runs[runs["status"] != "ok"]
    lines = []
    for message, same in bad.groupby(bad["status"] + ": " + bad["error"].fillna(""), sort=False):
        first = same.iloc[0]
        lines.append(f"- {message.rstrip(': ')}: {len(same)} of {len(runs)} runs, the first "
                     f"on {student_scene(first)} at T = {cell(first['T'])}")
    return ["Runs that were not ok:", ""] + lines + [""] if lines else []


def _judging_stories(judged: pd.DataFrame, grading: Grading) -> list[str]:
    """A section per judging scene the check found something on; one for the T it found the
    same thing at, as most broken programs break a scene the same way at every T."""
    found = judged[(judged["status"] == "ok") & judged["check"].notna()
                   & ~judged["check"].isin(PASSED)]
    if found.empty:
        return []
    found = found.assign(said=found.apply(lambda r: _words(r)(r["check_detail"]), axis=1))
    lines = []
    for (scene, _), runs in found.groupby(["scene_file", "said"], sort=False):
        threads = ", ".join(cell(t) for t in runs["T"])
        lines += [f"### {scene}, T = {threads}", ""] + _findings(runs.iloc[0], grading)
    return lines


def _timing_table(timed: pd.DataFrame) -> pd.DataFrame:
    rows = []
    for t, runs in timed.groupby("T"):
        ok = runs[runs["status"] == "ok"]
        statuses = runs["status"].value_counts()
        judged = ok.iloc[0] if not ok.empty else None
        # started on a busier machine than the sweep's start (psweep's busy_tasks): excluded
        # from the points unless the config counts them, as the points table says
        busy = int((ok["busy_tasks"].fillna(0) > 0).sum()) if "busy_tasks" in ok else 0
        rows.append({"T": t, "runs": len(runs),
                     "status": ", ".join(f"{n} {s}" for s, n in statuses.items()),
                     "busy": busy,
                     "min_s": ok["process_s"].min() if not ok.empty else float("nan"),
                     "median_s": ok["process_s"].median() if not ok.empty else float("nan"),
                     "timed run": _own_verdict(judged, False),
                     "judging run": _own_verdict(judged, True),
                     "verdict": worst_verdict(runs)[0]})
    return pd.DataFrame(rows)


def _own_verdict(row, judging_run: bool) -> str:
    """The verdict of one output alone, from its check report; '-' where there is none (no ok
    run, or a judging run that did not end ok)."""
    report = _check_report(row, judging_run)[0] if row is not None else None
    return str(report.get("verdict", "-")) if report else "-"


def _timing_stories(timed: pd.DataFrame, grading: Grading) -> list[str]:
    """A section per T whose verdict is not exact or consistent, T ascending: the verdict as
    the table has it, what made it where neither output alone did (a timed run that did less
    than its judging run, a repetition that ended elsewhere), then the timed run's and the
    judging run's findings."""
    lines = []
    for t, runs in timed.groupby("T"):
        ok = runs[runs["status"] == "ok"]
        verdict, detail = worst_verdict(runs)
        if ok.empty or verdict in PASSED:
            continue
        judged = ok.iloc[0]
        lines += [f"### T = {cell(t)}: {verdict}", ""]
        if verdict not in (_own_verdict(judged, False), _own_verdict(judged, True)):
            lines += [f"**{verdict}**: {_words(judged)(detail)}".rstrip(": "), ""]
        lines += ["The timed run (perf mode, its final state):", ""]
        lines += _findings(judged, grading)
        lines += ["The judging run (print mode, every step):", ""]
        report, _ = _check_report(judged, judging_run=True)
        lines += (_findings(judged, grading, judging_run=True) if report else
                  ["no check report: the judging run did not end ok (the verdict above)", ""])
    return lines


def _points(result: dict) -> list[str]:
    """The grade's tests as results.json has them, and the leaderboard."""
    tests = pd.DataFrame([{"test": t["name"], "score": t["score"], "of": t["max_score"],
                           "output": t["output"]} for t in result["tests"]])
    lines = ["## Points", "", markdown_table(tests)]
    if result["leaderboard"]:
        lines += ["Leaderboard: " + "; ".join(f"{e['name']}: {cell(float(e['value']))}"
                                              for e in result["leaderboard"]), ""]
    return lines


def submission_report(grade: pd.Series, entry, program: dict, grading: Grading) -> str:
    """`grade`: the submission's row of the grade board; `entry`: its plan.Submission;
    `program`: meta.json's record of it (empty when it was not run)."""
    name = grade["name"]
    result = grading.results[name]
    total = sum(t["max_score"] for t in result["tests"])
    lines = [f"# {entry.shown}", "",
             f"**{grade['verdict']}**, rank {grade['rank']} of {grading.count}, "
             f"{cell(float(result['score']))} of {cell(float(total))} points"
             + (f"; on {grade['scene']}: {grade['first_violation']}"
                if grade["first_violation"] and grade["scene"] else "")
             + (f"; {entry.note}" if entry.note else ""), ""]
    if entry.source is not None and (entry.build_log or entry.path is not None):
        lines += ["## Build", "", f"Built confined from the folder {entry.shown}; the end of its "
                  "log:", "", "```",
                  entry.build_log.rstrip().replace("```", "` ` `") or "(empty)", "```", ""]
    if entry.path is None:
        return "\n".join(lines)
    how = ("Run confined as" if grading.confined else "Run unconfined (--unconfined), as the "
           "grader and with its files, as")
    command = " ".join([entry.path.name, *grading.args])
    lines += [f"{how} `{command} < scene` with OMP_NUM_THREADS = T "
              f"(executable {program.get('executable_hash') or 'unreadable'}; what it may do: "
              "docs/programs.md, \"Confinement\").", ""]
    if grading.drawn:
        lines += [grading.drawn[0].upper() + grading.drawn[1:] + ".", ""]
    lines += ["## Every scene", ""]
    mine = grading.runs[grading.runs["engine"] == name]
    judged = mine[mine["scene"] != grading.timing_scene]
    judged = judged.assign(order=judged["scene_file"].map(list(grading.tests).index)).sort_values(
        ["order", "T"], kind="stable")
    timed = mine[mine["scene"] == grading.timing_scene].sort_values("T", kind="stable")
    lines.append(markdown_table(_scene_table(judged, timed, grading)))
    lines += _failures(pd.concat([judged, timed]))
    lines += _judging_stories(judged, grading)
    lines += _points(result)
    lines += [f"## Timing: {grading.timing_scene}", ""]
    if timed.empty:
        return "\n".join(lines + ["Not timed: no judging run of it ended ok."])
    lines += ["Whole process, repetitions after the warm-up. Each T's first ok run is judged "
              "twice: its own output (the timed run, perf mode: the final state), and a "
              "judging run of the same particles (print mode, step by step), whose final state "
              "the timed run's must be; the verdict is the worse of the two, and every later "
              "repetition must end in the same final state. `busy`: the ok runs started while "
              "more tasks ran than when the sweep began, which earn no points unless the grade "
              "config counts them (the points above say how many were excluded).", "",
              markdown_table(_timing_table(timed)),
              f"Time at T = 1: {cell(grade['time_T1_s'])} s; best {cell(grade['best_s'])} s at "
              f"T = {cell(grade['best_T'])}; speed-up {cell(grade['speedup'])}; against the "
              f"fastest exact engine {cell(grade['vs_fastest_exact'])} (above 1: faster).", ""]
    lines += _timing_stories(timed, grading)
    return "\n".join(lines)
