"""The grade scoreboard: one row per submission (and per engine of the timing sweep), from the
scoreboard's per-scene rows (analysis/scoreboard/board.py) over every sweep of the grading.
MEANINGS says what each column is; the page (scoreboard_page) says it under the table.

The timing scene counts for the verdict too: a submission that is right on the short scenes and
prints garbage, crashes or times out on the large one has no time to rank it by. Rows sort by
verdict, then by best_s, so a violating, malformed or failed submission is never ranked ahead of
a correct one. The overall verdict names one scene; the column of each scene names them all, so
a format problem on one scene hides nothing judged on the others. Likewise a verdict per T
(`verdict_T1`, `verdict_T2`, ...): a race that fails T = 2 hides nothing of what T = 1 did.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import pandas as pd

from analysis.common.declaration import Declaration
from analysis.common.markdown import markdown_table
from analysis.scoreboard.board import VERDICT_ORDER, scene_label, scoreboard

GRADE_ORDER = VERDICT_ORDER + ["failed"]
TIMING_COLUMNS = ["time_T1_s", "best_s", "best_T", "speedup", "vs_fastest_exact"]
TIMING = "timing"  # the timing scene's column; each judging scene's is its file's stem
HEAD_COLUMNS = ["rank", "name", "kind", "score", "verdict", "scene", "first_violation"]
# Where a submission was timed (gradescope.beside): its speed points are its times over the
# reference's there.
BESIDE_COLUMNS = ["reference_s", "node"]
TAIL_COLUMNS = TIMING_COLUMNS + BESIDE_COLUMNS + ["report"]
# The names a judging scene's column may not take.
BOARD_COLUMNS = set(HEAD_COLUMNS + TAIL_COLUMNS) | {TIMING}

MEANINGS = {
    "rank": "verdict first, then best_s: a violating, malformed or failed submission is never "
            "ranked ahead of a correct one, however fast",
    "name": "the submission's file name (escaped: a newline as \\n), or the lab's reference "
            "timed beside them",
    "kind": "`program`, a submission; `lab`, the lab's own program (plain_allpairs: the model "
            "written the plain way), judged and timed as a submission is; `engine`, one of "
            "psim's (neither of the lab's has a score or a report)",
    "score": "its points in grades.csv and results.json (judging and speed)",
    "verdict": "the worst over every scene, judging and timing: `exact` < `consistent` < "
               "`ambiguous` < `unchecked` < `violations` < `malformed` < `failed` (a run "
               "crashed, hung, printed without end, exited nonzero or could not be executed)",
    "verdict_T": "the worst over every scene at that T alone: a failure at T = 2 (a race, a "
                 "thread that cannot start) leaves T = 1's verdict to be read",
    "scene": "where that verdict came from (the first such scene in the config's order)",
    "first_violation": "what the check found there: the time unit of the first violation and "
                       "what the model does there, the malformed line, or the failed run's "
                       "status and error",
    "time_T1_s": "timing scene: the least whole-process time at T = 1",
    "best_s": "timing scene: the least whole-process time at any T",
    "best_T": "timing scene: the T of best_s",
    "speedup": "time_T1_s / best_s",
    "vs_fastest_exact": "the fastest exact engine's best_s / this one's: above 1, faster",
    "reference_s": "the first reference of the speed points (timing.engines), its least "
                   "whole-process time at the smallest T, timed in the same sweep as this "
                   "submission, interleaved with it on the same node: what its speed points "
                   "are against",
    "node": "the node (Slurm's name, else the host) the timed runs ran on",
    "report": "its report: each scene and T, the check's findings, its points and its timing",
}


@dataclass
class SceneColumn:
    label: str   # the scoreboard's scene label (scene_label)
    column: str  # its column of the board: the scene file's stem, or TIMING
    where: str   # the scene as the page names it: its file, or the timing scene
    about: str   # what it tests: the page's line on its column


def with_scenes(runs: pd.DataFrame) -> pd.DataFrame:
    """runs with the scoreboard's scene label of each row."""
    return runs.assign(scene=runs.apply(scene_label, axis=1))


def student_scene(row) -> str:
    """The scene of a run as a student knows it: its file, or the timing scene."""
    return row["scene_file"] if isinstance(row["scene_file"], str) else "the timing scene"


def in_student_words(text: str, results: str, scene: str) -> str:
    """A check's message with the grader's file of an output
    (RESULTS/outputs/2c11df556603.out:3, the judging run's .judge.out) named as the student
    knows it: their output for the scene, and its line."""
    output = re.compile(r"(?:line \d+: )?" + re.escape(results)
                        + r"/outputs/[0-9a-f]+(\.judge)?\.out:(\d+)")
    return output.sub(lambda m: f"your output for {scene}"
                      + (" in print mode (the judging run)" if m.group(1) else "")
                      + f", line {m.group(2)}", text)


def failure(runs: pd.DataFrame) -> str:
    """The first failed run of a submission on a scene, as its row in runs.csv says."""
    bad = runs[runs["status"] != "ok"]
    if bad.empty:
        return ""
    row = bad.iloc[0]
    error = row["error"] if isinstance(row["error"], str) else ""
    return f"{row['status']}: {error}".rstrip(": ")


def scene_verdicts(labelled: pd.DataFrame, programs: set[str],
                   declaration: Declaration) -> pd.DataFrame:
    """The scoreboard's per-scene rows from runs with their scene labels (with_scenes) and
    `results` folders, `failed` where a run of a submission was not ok: a crash at T = 2 after
    a right output at T = 1 (a race) fails it as much as one at T = 1. A submission's first
    violation names its output as the student knows it (in_student_words)."""
    board = scoreboard(labelled, programs, declaration)
    for i, row in board[board["kind"] == "program"].iterrows():
        mine = labelled[(labelled["engine"] == row["name"]) & (labelled["scene"] == row["scene"])]
        problem = failure(mine)
        if problem:
            board.loc[i, ["verdict", "first_violation"]] = ["failed", problem]
        else:
            board.loc[i, "first_violation"] = in_student_words(
                row["first_violation"], mine["results"].iloc[0], student_scene(mine.iloc[0]))
    return board


def verdict_column(t: float) -> str:
    """The board's column of the verdict at one T."""
    return f"verdict_T{t:g}"


def is_board_column(name: str) -> bool:
    """Whether a judging scene named `name` would take a column the board has already."""
    return name in BOARD_COLUMNS or re.fullmatch(r"verdict_T[0-9.e+-]+", name) is not None


def worst_per_T(by_T: dict[float, pd.DataFrame]) -> pd.DataFrame:
    """name x verdict_T<t>: the worst verdict over every scene at each T, from scene_verdicts'
    rows of that T's runs alone (`by_T`: T -> those rows)."""
    columns = {}
    for t, rows in sorted(by_T.items()):
        order = rows["verdict"].map(GRADE_ORDER.index)
        worst = rows.assign(order=order).sort_values("order").groupby("name", sort=False).last()
        columns[verdict_column(t)] = worst["verdict"]
    return pd.DataFrame(columns)


def grade_board(per_scene: pd.DataFrame, scenes: list[SceneColumn],
                scores: dict[str, float],
                by_T: dict[float, pd.DataFrame] | None = None,
                beside: dict[str, dict] | None = None) -> pd.DataFrame:
    """One row per name from scene_verdicts' rows; `scenes` in the config's order (judging
    scenes, then the timing scene); `scores`: each submission's points (gradescope.py);
    `by_T`: scene_verdicts' rows of each T's runs alone, for a verdict column per T; `beside`:
    name -> its BESIDE_COLUMNS (gradescope.beside), empty for a name not timed."""
    beside = beside or {}
    labels = [s.label for s in scenes] + [""]  # "": an entry that was not graded
    per_scene = per_scene.assign(scene_order=per_scene["scene"].map(labels.index),
                                 order=per_scene["verdict"].map(GRADE_ORDER.index))
    timing_scene = scenes[-1].label if scenes else None
    rows = []
    for name, mine in per_scene.groupby("name", sort=False):
        worst = mine.sort_values(["order", "scene_order"], ascending=[False, True]).iloc[0]
        timed = mine[mine["scene"] == timing_scene]
        times = timed.iloc[0][TIMING_COLUMNS] if not timed.empty else pd.Series(
            float("nan"), index=TIMING_COLUMNS)
        verdicts = dict(zip(mine["scene"], mine["verdict"]))
        program = worst["kind"] == "program"
        rows.append({"name": name, "kind": worst["kind"],
                     "score": scores.get(name, float("nan")), "verdict": worst["verdict"],
                     "scene": worst["scene"] if worst["verdict"] not in ("exact", "consistent")
                     else "", "first_violation": worst["first_violation"],
                     # nan, shown '-': not run there (an engine on a judging scene; a
                     # submission with no judging run ended ok is not timed)
                     **{s.column: verdicts.get(s.label, float("nan")) for s in scenes},
                     **times.to_dict(),
                     **{c: beside.get(name, {}).get(c, float("nan") if c == "reference_s" else "")
                        for c in BESIDE_COLUMNS},
                     "report": f"reports/{name}.html" if program else ""})
    board = pd.DataFrame(rows)
    board["order"] = board["verdict"].map(GRADE_ORDER.index)
    board = board.sort_values(["order", "best_s"], na_position="last", kind="stable")
    board["rank"] = range(1, len(board) + 1)
    per_T = worst_per_T(by_T or {})
    board = board.join(per_T, on="name")  # nan, shown '-': no run at that T
    after = HEAD_COLUMNS.index("verdict") + 1
    head = HEAD_COLUMNS[:after] + list(per_T.columns) + HEAD_COLUMNS[after:]
    return board[head + [s.column for s in scenes] + TAIL_COLUMNS].reset_index(drop=True)


def scoreboard_page(board: pd.DataFrame, scenes: list[SceneColumn], title: str,
                    intro: str) -> str:
    """scoreboard.md: the board with a link to each report, then a line per column."""
    shown = board.assign(report=board["report"].map(
        lambda path: f"[report]({path})" if path else ""))
    lines = [f"# {title}", "", intro, "", markdown_table(shown), "What each column says:", ""]
    lines += [f"- `{column}`: {MEANINGS[column]}" for column in HEAD_COLUMNS]
    lines += [f"- `{column}`: {MEANINGS['verdict_T']}" for column in board.columns
              if column.startswith("verdict_T")]
    for scene in scenes:
        lines.append(f"- `{scene.column}`: the verdict on {scene.where} (the worst over its T; "
                     f"the report has each): {scene.about}")
    lines += [f"- `{column}`: {MEANINGS[column]}" for column in TAIL_COLUMNS]
    return "\n".join(lines) + "\n"
