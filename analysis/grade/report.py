"""One Markdown report per submission: its grade, every judging scene and T with the check's
verdict and, where it found something, the first violations and ambiguous time units in full
(from the check's report beside the output, DIR/outputs/<config_id>.check.json), then its
timing. `runs` is every sweep's runs with the scene label (board.with_scenes) and `results`, the
folder each row came from."""
from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from analysis.common.markdown import cell, markdown_table

SHOWN = 5  # violations and ambiguous time units shown per check; the .check.json has the rest


def _check_path(row) -> Path:
    """The psim check report psweep kept for the run of this row."""
    return Path(row["results"]) / "outputs" / f"{row['config_id']}.check.json"


def _check_report(row) -> dict | None:
    try:
        return json.loads(_check_path(row).read_text())
    except (OSError, json.JSONDecodeError):
        return None


def _listed(title: str, items: list[dict], total: int, source: Path) -> list[str]:
    lines = [f"{title} (the first {min(len(items), SHOWN)} of {total}):", ""]
    for item in items[:SHOWN]:
        particles = ", ".join(str(p) for p in item.get("particles", []))
        kind = f"{item['kind']}: " if "kind" in item else ""
        # The check gives no size where there is none to give (a value that is not finite).
        off = item.get("difference")
        size = f" (off by {cell(float(off))})" if isinstance(off, (int, float)) else ""
        lines.append(f"- time unit {item.get('step')}, particles {particles}: {kind}"
                     f"{item.get('detail', '')}{size}")
    if total > SHOWN:
        lines.append(f"- ... the rest in `{source}`")
    return lines + [""]


def _findings(row) -> list[str]:
    """What the check found for one judged output, in full."""
    report = _check_report(row)
    source = _check_path(row)
    if report is None:
        return [f"{row['check']}: {row['check_detail']}", ""]
    lines = [f"{report.get('verdict')}: {report.get('summary')}", ""]
    kinds = report.get("kinds") or {}
    if kinds:
        lines += ["Violations per kind: " + ", ".join(f"{k}: {n}" for k, n in kinds.items()), ""]
    violations = report.get("violations") or []
    if violations:
        lines += _listed("Violations", violations, int(report.get("violation_count",
                                                                 len(violations))), source)
    ambiguous = report.get("ambiguous") or []
    if ambiguous:
        lines += _listed("Ambiguous within rounding", ambiguous, len(ambiguous), source)
    return lines


def _judging_table(judged: pd.DataFrame, tests: dict[str, str]) -> pd.DataFrame:
    """A row per scene, in the config's order: the verdict at each T (the run's status where it
    was not ok) and the first time unit any T broke the model."""
    rows = []
    for scene, runs in judged.groupby("scene_file", sort=False):
        row = {"scene": scene, "tests": tests.get(scene, "")}
        for _, run in runs.iterrows():
            row[f"T={cell(run['T'])}"] = run["check"] if run["status"] == "ok" else run["status"]
        row["first step"] = runs["check_first_step"].min()
        rows.append(row)
    return pd.DataFrame(rows)


def _failures(runs: pd.DataFrame) -> list[str]:
    """Runs that were not ok, one line per message: a crash is the same crash on every scene."""
    bad = runs[runs["status"] != "ok"]
    lines = []
    for message, same in bad.groupby(bad["status"] + ": " + bad["error"].fillna(""), sort=False):
        first = same.iloc[0]
        lines.append(f"- {message.rstrip(': ')}: {len(same)} of {len(runs)} runs, the first "
                     f"{first['scene_file']} at T = {cell(first['T'])}")
    return ["Runs that were not ok:", ""] + lines + [""] if lines else []


def _timing_table(mine: pd.DataFrame) -> pd.DataFrame:
    rows = []
    for t, runs in mine.groupby("T"):
        ok = runs[runs["status"] == "ok"]["process_s"]
        statuses = runs["status"].value_counts()
        rows.append({"T": t, "runs": len(runs),
                     "status": ", ".join(f"{n} {s}" for s, n in statuses.items()),
                     "min_s": ok.min() if not ok.empty else float("nan"),
                     "median_s": ok.median() if not ok.empty else float("nan"),
                     "check": next((c for c in runs["check"] if isinstance(c, str)), "-")})
    return pd.DataFrame(rows)


def submission_report(grade: pd.Series, count: int, runs: pd.DataFrame, tests: dict[str, str],
                      timing_scene: str, program: dict, entry) -> str:
    """`grade`: the submission's row of the grade board, `count` its number of rows; `runs`: as
    the module says; `tests`: scene file -> what it tests; `program`: meta.json's record of it
    (empty when it was not run); `entry`: its plan.Submission."""
    name = grade["name"]
    mine = runs[runs["engine"] == name]
    lines = [f"# {entry.shown}", "",
             f"**{grade['verdict']}**, rank {grade['rank']} of {count}"
             + (f"; on {grade['scene']}: {grade['first_violation']}"
                if grade["first_violation"] and grade["scene"] else "")
             + (f"; {entry.note}" if entry.note else ""), ""]
    if entry.path is None:
        return "\n".join(lines)
    lines += [f"Run confined as `{entry.path.name} < scene` with OMP_NUM_THREADS = T "
              f"(executable {program.get('executable_hash') or 'unreadable'}; what it may do: "
              "docs/programs.md, \"Confinement\").", "", "## Judging scenes", ""]
    judged = mine[mine["scene"] != timing_scene]
    judged = judged.assign(order=judged["scene_file"].map(list(tests).index)).sort_values(
        ["order", "T"], kind="stable")
    lines.append(markdown_table(_judging_table(judged, tests)))
    lines += _failures(judged)
    found = judged[(judged["status"] == "ok") & judged["check"].notna()
                   & ~judged["check"].isin(["exact", "consistent"])]
    # Most broken programs break a scene the same way at every T: one section for those T.
    for (scene, _), runs in found.groupby(["scene_file", "check_detail"], sort=False):
        threads = ", ".join(cell(t) for t in runs["T"])
        lines += [f"### {scene}, T = {threads}", ""] + _findings(runs.iloc[0])
    timed = mine[mine["scene"] == timing_scene]
    lines += [f"## Timing: {timing_scene}", "",
              "Whole process, repetitions after the warm-up; the check judges the first ok run "
              "of each T on its final state (perf mode) and a judging run of the same "
              "particles in print mode step by step.", "",
              markdown_table(_timing_table(timed)),
              f"Time at T = 1: {cell(grade['time_T1_s'])} s; best {cell(grade['best_s'])} s at "
              f"T = {cell(grade['best_T'])}; speed-up {cell(grade['speedup'])}; against the "
              f"fastest exact engine {cell(grade['vs_fastest_exact'])} (above 1: faster).", ""]
    for _, row in timed[timed["check"].isin(["violations", "malformed", "ambiguous"])].iterrows():
        lines += [f"### Timing check, T = {cell(row['T'])}", ""] + _findings(row)
    return "\n".join(lines)
