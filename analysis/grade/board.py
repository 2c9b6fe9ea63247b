"""The grade scoreboard: one row per submission (and per engine of the timing sweep), from the
scoreboard's per-scene rows (analysis/scoreboard/board.py) over every sweep of the grading.

  verdict           the worst over every scene, judging and timing (GRADE_ORDER); `failed` where
                    a run on a scene was not ok: the submission crashed, hung, printed without
                    end, exited nonzero or could not be executed there
  scene             where that verdict came from (the first such scene in the config's order)
  first_violation   what the check found there, or the status and error of the failed run
  time_T1_s ... vs_fastest_exact   the timing scene's scoreboard row

The timing scene counts for the verdict too: a submission that is right on the short scenes and
prints garbage, crashes or times out on the large one has no time to rank it by. Rows sort by
verdict, then by best_s, so a violating, malformed or failed submission is never ranked ahead of
a correct one.
"""
from __future__ import annotations

import pandas as pd

from analysis.common.declaration import Declaration
from analysis.scoreboard.board import VERDICT_ORDER, scene_label, scoreboard

GRADE_ORDER = VERDICT_ORDER + ["failed"]
TIMING_COLUMNS = ["time_T1_s", "best_s", "best_T", "speedup", "vs_fastest_exact"]
COLUMNS = ["rank", "name", "kind", "verdict", "scene", "first_violation"] + TIMING_COLUMNS


def with_scenes(runs: pd.DataFrame) -> pd.DataFrame:
    """runs with the scoreboard's scene label of each row."""
    return runs.assign(scene=runs.apply(scene_label, axis=1))


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
    """The scoreboard's per-scene rows from runs with their scene labels (with_scenes),
    `failed` where a run of a submission was not ok: a crash at T = 2 after a right output at
    T = 1 (a race) fails it as much as one at T = 1."""
    board = scoreboard(labelled, programs, declaration)
    for i, row in board[board["kind"] == "program"].iterrows():
        problem = failure(labelled[(labelled["engine"] == row["name"])
                                   & (labelled["scene"] == row["scene"])])
        if problem:
            board.loc[i, ["verdict", "first_violation"]] = ["failed", problem]
    return board


def grade_board(per_scene: pd.DataFrame, timing_scene: str, scene_order: list[str]) -> pd.DataFrame:
    """One row per name from scene_verdicts' rows; `scene_order` lists the scene labels in the
    config's order (judging scenes, then the timing scene)."""
    per_scene = per_scene.assign(
        scene_order=per_scene["scene"].map(scene_order.index),
        order=per_scene["verdict"].map(GRADE_ORDER.index))
    rows = []
    for name, mine in per_scene.groupby("name", sort=False):
        worst = mine.sort_values(["order", "scene_order"], ascending=[False, True]).iloc[0]
        timed = mine[mine["scene"] == timing_scene]
        times = timed.iloc[0][TIMING_COLUMNS] if not timed.empty else pd.Series(
            float("nan"), index=TIMING_COLUMNS)
        rows.append({"name": name, "kind": worst["kind"], "verdict": worst["verdict"],
                     "scene": worst["scene"] if worst["verdict"] not in ("exact", "consistent")
                     else "", "first_violation": worst["first_violation"], **times.to_dict()})
    board = pd.DataFrame(rows)
    board["order"] = board["verdict"].map(GRADE_ORDER.index)
    board = board.sort_values(["order", "best_s"], na_position="last", kind="stable")
    board["rank"] = range(1, len(board) + 1)
    return board[COLUMNS].reset_index(drop=True)
