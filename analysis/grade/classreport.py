"""OUT/class.md and .html: a graded class at a glance, for the staff (issue 54, item 3).

What a scoreboard of one row per submission does not answer: how the scores spread; per judging
scene, how many submissions got each verdict and the rule most of them broke there, with
examples; who is correct but slow and who fast but wrong (one point per submission); how noisy
each timing window was, read from the reference's own runs; and which submissions printed
byte-identical outputs on every scene where they are not the reference's text (a hint worth a
look, not a verdict: every exact program prints the reference's text, so identical exact outputs
say nothing).

Read from what the grading wrote: the board (scoreboard.csv's rows, names as shown), grades.csv,
and each judged run's check report and output (the runs' `results` folder, outputs/ID.*).
"""
from __future__ import annotations

import hashlib
import json
import os
from collections import Counter
from pathlib import Path

import pandas as pd

from analysis.common.figures import plt, save
from analysis.common.hover import tag
from analysis.common.markdown import cell, markdown_table
from analysis.common.page import write_pages
from analysis.grade.board import TIMING, SceneColumn

VERDICTS = ("exact", "consistent", "ambiguous", "violations", "malformed", "failed")
EXAMPLES = 3  # submissions named per rule


def _judged_runs(labelled: pd.DataFrame, shown: dict[str, str],
                 scenes: list[SceneColumn]) -> pd.DataFrame:
    """The submissions' runs on the judging scenes (not the timing scene), one per
    configuration, `name` as shown."""
    judging = {s.label for s in scenes if s.column != TIMING}
    runs = labelled[labelled["engine"].isin(shown) & labelled["scene"].isin(judging)]
    return runs.drop_duplicates("config_id").assign(name=runs["engine"].map(shown))


def _kinds(run) -> set[str]:
    """The kinds of violation psim check found in one run (its check report), none if absent."""
    path = Path(run["results"]) / "outputs" / f"{run['config_id']}.check.json"
    try:
        return set(json.loads(path.read_text()).get("kinds", {}))
    except (OSError, ValueError):
        return set()


def _output_hash(run) -> str | None:
    path = Path(run["results"]) / "outputs" / f"{run['config_id']}.out"
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def scene_table(board: pd.DataFrame, judged: pd.DataFrame, scenes: list[SceneColumn],
                reports: dict[str, str]) -> pd.DataFrame:
    """Per judging scene: how many submissions got each verdict, and the rule most of them broke
    there (psim check's kind of violation), with up to EXAMPLES submissions that broke it."""
    programs = board[board["kind"] == "program"]
    rows = []
    for scene in scenes:
        if scene.column == TIMING:
            continue
        counts = Counter(programs[scene.column].dropna())
        broke: dict[str, set[str]] = {}
        for _, run in judged[judged["scene"] == scene.label].iterrows():
            for kind in _kinds(run):
                broke.setdefault(kind, set()).add(run["name"])
        rule = max(sorted(broke), key=lambda k: len(broke[k]), default=None)
        examples = ", ".join(f"[{n}]({reports[n]})" if n in reports else n
                             for n in sorted(broke[rule])[:EXAMPLES]) if rule else ""
        rows.append({"scene": scene.where, **{v: counts.get(v, 0) for v in VERDICTS},
                     "rule most broken": f"{rule} ({len(broke[rule])})" if rule else "none",
                     "for example": examples})
    return pd.DataFrame(rows)


def identical_groups(judged: pd.DataFrame) -> list[list[str]]:
    """Submissions whose outputs are byte-identical on every judging scene and T, where some
    output is not exact (the reference's text): groups of two and more, names sorted."""
    by_name: dict[str, tuple] = {}
    for name, runs in judged.groupby("name"):
        if (runs["check"] == "exact").all():
            continue
        keys = tuple(sorted((str(r["scene"]), float(r["T"]) if pd.notna(r["T"]) else 0.0,
                             _output_hash(r)) for _, r in runs.iterrows()))
        if all(k[2] is not None for k in keys):
            by_name[name] = keys
    groups: dict[tuple, list[str]] = {}
    for name, keys in by_name.items():
        groups.setdefault(keys, []).append(name)
    return sorted((sorted(g) for g in groups.values() if len(g) > 1), key=lambda g: g[0])


# A run of the reference this far above its least is taken as slowed (docs/programs.md, "The
# reference": the host's spells slow a run by a third to a half).
SLOWED = 1.15


def noise_table(timed: pd.DataFrame, reference: str, repetitions: int,
                out: Path) -> pd.DataFrame:
    """Per timing window (the runs' `results` folder, inside OUT) and T: the reference's ok
    runs, its least time, the share p of them more than SLOWED times it, and p ** repetitions,
    the chance that every timed run of a submission fell in a slow spell of such a window."""
    runs = timed[(timed["engine"] == reference) & (timed["status"] == "ok")
                 & timed["process_s"].notna()]
    rows = []
    for (window, t), group in runs.groupby(["results", "T"]):
        times = group["process_s"]
        share = float((times > SLOWED * times.min()).mean())
        rows.append({"window": os.path.relpath(window, out), "T": t, "runs": len(times),
                     "least (s)": times.min(), "slowed": f"{share:.0%}",
                     f"all {repetitions} of a submission slowed": f"{share ** repetitions:.1%}"})
    return pd.DataFrame(rows)


def _score_figure(grades: pd.DataFrame, out: Path) -> Path:
    fig, ax = plt.subplots(figsize=(6, 3.2))
    ax.hist(grades["score"], bins=[10 * k for k in range(11)], color="#4c72b0",
            edgecolor="white")
    ax.set_xlabel("score (of 100)")
    ax.set_ylabel("submissions")
    ax.set_title("How the scores spread")
    return save(fig, out / "class" / "scores", formats=("png",))


def _speed_figure(grades: pd.DataFrame, out: Path) -> Path:
    timed = grades[grades["best_s"].notna()]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.scatter(timed["judging_score"], timed["best_s"], color="#dd8452")
    tag(ax, timed["judging_score"], timed["best_s"],
        [f"submission={n} judging={j:.3g}" for n, j in
         zip(timed["name"], timed["judging_score"])])
    ax.set_yscale("log")
    ax.set_xlabel("judging points (correctness)")
    ax.set_ylabel("best time on the timing scene (s)")
    ax.set_title("Correct but slow (top right), fast but wrong (bottom left)")
    return save(fig, out / "class" / "speed", formats=("png",))


def class_page(board: pd.DataFrame, labelled: pd.DataFrame, shown: dict[str, str],
               scenes: list[SceneColumn], out: Path, title: str, timed: pd.DataFrame,
               reference: str | None, repetitions: int) -> Path:
    """Writes OUT/class.md and class.html (figures in OUT/class/); returns the page. `board`:
    the scoreboard's rows, names as shown; `shown`: psweep's name -> the name shown; `timed`:
    the timing windows' runs, `reference` the first of timing.engines (None: no noise table)."""
    # Names as written: a submission may be called "nan" or "1e3".
    grades = pd.read_csv(out / "grades.csv", dtype={"name": str}, keep_default_na=False)
    for column in ("score", "judging_score", "best_s"):
        grades[column] = pd.to_numeric(grades[column], errors="coerce")
    reports = {name: f"reports/{program}.html" for program, name in shown.items()}
    judged = _judged_runs(labelled, shown, scenes)
    scores = grades["score"]
    lines = [f"# {title}", ""]
    if grades.empty:
        return write_pages(out / "class.md", "\n".join(lines + ["No submission was graded."]))
    lines += ["## Scores", "",
              f"{len(grades)} submissions: median {cell(scores.median())}, quartiles "
              f"{cell(scores.quantile(0.25))} and {cell(scores.quantile(0.75))}, from "
              f"{cell(scores.min())} to {cell(scores.max())}.", "",
              f"![scores]({_score_figure(grades, out).relative_to(out)})", "",
              "## Judging scenes", "",
              "How many submissions got each verdict on each scene (the worst over T), and the "
              "rule most of them broke there: psim check's kind of violation, with the number "
              "of submissions that broke it.", "",
              markdown_table(scene_table(board, judged, scenes, reports)), "",
              "## Correctness and speed", ""]
    if grades["best_s"].notna().any():
        lines += [f"![correctness and speed]({_speed_figure(grades, out).relative_to(out)})",
                  ""]
    untimed = grades[grades["best_s"].isna()]["name"].tolist()
    if untimed:
        lines += [f"Not timed or not counted ({len(untimed)}): {', '.join(sorted(untimed))}.",
                  ""]
    noise = noise_table(timed, reference, repetitions, out) if reference else pd.DataFrame()
    if not noise.empty:
        lines += ["## The timing's noise", "",
                  f"The reference {reference}'s runs in each timing window: the share slowed, "
                  f"more than {SLOWED:g} times its least (a slow spell of the host, unseen from "
                  "inside: docs/programs.md, \"The reference\"), and the chance that all of a "
                  "submission's runs were slowed at that share. Where that chance is more than "
                  "a few percent, some submissions' speed points are low by chance: time them "
                  "again on a quieter machine.", "", markdown_table(noise), ""]
    groups = identical_groups(judged)
    lines += ["## Byte-identical outputs", "",
              "Submissions whose outputs are the same bytes on every judging scene and T, where "
              "they are not the reference's (a hint worth a look, not a verdict):", ""]
    lines += [f"- {', '.join(g)}" for g in groups] or ["None."]
    return write_pages(out / "class.md", "\n".join(lines))
