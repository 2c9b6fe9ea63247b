"""The scoreboard: per scene, one row per program and engine, judged first and timed second.

  verdict           a program's: the worst `psim check` verdict over its configurations on the
                    scene (runs.csv's check column, one per configuration); `unchecked` when
                    none judged it (no ok run, or the check failed). An engine's: `exact` when
                    psim's declaration says it matches the reference bit for bit (the model, by
                    construction and by the test suite), else `unchecked`
  first_violation   what the check found in the worst configuration: the time unit of its first
                    violation and what the model does there, or the malformed line; for
                    `unchecked`, why nothing judged it
  time_T1_s         the minimum process_s at T=1 (a program that ignores T ran once, as T=1)
  best_s, best_T    the minimum process_s over every T, and the T that gave it
  speedup           time_T1_s / best_s
  vs_fastest_exact  the best_s of the fastest exact engine on the scene / best_s: above 1, faster
                    than every engine that follows the model bit for bit

Times are whole processes (process_s) for programs and engines alike: a program has no timer of
its own, and psim's loop time would leave out the start-up, input and output the program's time
includes. Rows sort by verdict (VERDICT_ORDER), then by best_s: a program that breaks the model
or prints malformed output is never ranked ahead of a correct one, however fast.
"""
from __future__ import annotations

import pandas as pd

from analysis.common.declaration import Declaration
from analysis.common.load import DEFAULT_READINGS, SCENE_PARAMS
from analysis.common.labels import fmt
from analysis.common.markdown import markdown_table

VERDICT_ORDER = ["exact", "consistent", "ambiguous", "unchecked", "violations", "malformed"]
# The scene: what is simulated, whoever simulates it (T and the engine aside).
COLUMNS = ["scene", "rank", "name", "kind", "verdict", "first_violation", "time_T1_s", "best_s",
           "best_T", "speedup", "vs_fastest_exact"]


def reading(row) -> str:
    """The readings that are not the default ones, for a scene's label."""
    label = ""
    for column, default in DEFAULT_READINGS.items():
        value = row.get(column, default)
        if value not in (default, None) and value == value:
            label += f" {column}={value}"
    return label


def scene_label(row) -> str:
    if isinstance(row["scene_file"], str):
        return f"{row['scene_file']} K={fmt(row['slow_factor'])}{reading(row)}"
    label = " ".join(f"{key}={fmt(row[key])}" for key in ("N", "L", "r", "S"))
    label += f" K={fmt(row['slow_factor'])} seed={fmt(row['seed'])}"
    label += reading(row)
    if pd.notna(row["speed_min"]):
        label += f" speeds={fmt(row['speed_min'])}..{fmt(row['speed_max'])}"
    return label


def worst_verdict(mine: pd.DataFrame) -> tuple[str, str]:
    """The worst verdict of a program's rows on one scene, and its first violation; `unchecked`
    with the reason when no row was judged."""
    judged = mine[mine["check"].isin(VERDICT_ORDER)]
    if judged.empty:
        return "unchecked", _unjudged(mine)
    worst = judged.loc[judged["check"].map(VERDICT_ORDER.index).idxmax()]
    # The check's detail names the time unit of the first violation, or the malformed line.
    first = str(worst["check_detail"]) if worst["check"] in ("violations", "malformed") else ""
    return worst["check"], first


def _unjudged(mine: pd.DataFrame) -> str:
    """Why no row of a program on one scene has a verdict: no run was ok (how they ended), psim
    check could not judge one (its reason), or no check was recorded (a psweep without one)."""
    failed = mine[mine["check"].notna() & (mine["check"] != "")]
    if (mine["status"] != "ok").all():
        ended = mine["status"].value_counts().sort_index()
        return "no ok run: " + ", ".join(f"{n} {status}" for status, n in ended.items())
    if not failed.empty:
        return f"psim check could not judge it ({failed['check'].iloc[0]}): " \
               f"{failed['check_detail'].fillna('').astype(str).iloc[0]}".rstrip(": ")
    return "no check recorded for its runs"


def scoreboard(runs: pd.DataFrame, programs: set[str], declaration: Declaration) -> pd.DataFrame:
    """`runs` as load.py returns it; `programs`, the names meta.json lists under programs."""
    if runs.empty:
        return pd.DataFrame(columns=COLUMNS)
    exact_engines = declaration.exact_engines
    rows = []
    for _, scene in runs.groupby(SCENE_PARAMS, dropna=False, sort=False):
        label = scene_label(scene.iloc[0])
        for name, mine in scene.groupby("engine", sort=False):
            ok = mine[(mine["status"] == "ok") & mine["process_s"].notna()]
            program = name in programs
            if program:
                verdict, first = worst_verdict(mine)
            elif exact_engines is None:
                verdict, first = "unchecked", "meta.json has no psim declaration to say it is exact"
            elif name in exact_engines:
                verdict, first = "exact", ""
            else:
                verdict, first = "unchecked", "psim declares it not bit-identical to the reference"
            best = ok.loc[ok["process_s"].idxmin()] if not ok.empty else None
            serial = ok[ok["T"] == 1]["process_s"]
            rows.append({
                "scene": label, "name": name, "kind": "program" if program else "engine",
                "verdict": verdict, "first_violation": first,
                "time_T1_s": serial.min() if not serial.empty else float("nan"),
                "best_s": best["process_s"] if best is not None else float("nan"),
                "best_T": best["T"] if best is not None else float("nan"),
                "exact_engine": not program and verdict == "exact",
            })
    board = pd.DataFrame(rows)
    board["speedup"] = board["time_T1_s"] / board["best_s"]
    fastest = board[board["exact_engine"]].groupby("scene", sort=False)["best_s"].min()
    board["vs_fastest_exact"] = board["scene"].map(fastest) / board["best_s"]
    board["order"] = board["verdict"].map(VERDICT_ORDER.index)
    board = board.sort_values(["order", "best_s"], na_position="last", kind="stable")
    board["rank"] = board.groupby("scene", sort=False).cumcount() + 1
    scenes = list(dict.fromkeys(row["scene"] for row in rows))
    board["scene_order"] = board["scene"].map(scenes.index)
    board = board.sort_values(["scene_order", "rank"], kind="stable")
    return board[COLUMNS].reset_index(drop=True)


def scoreboard_markdown(board: pd.DataFrame) -> str:
    """One table per scene, for stdout and report.md."""
    parts = []
    for scene, rows in board.groupby("scene", sort=False):
        parts.append(f"**{scene}**\n\n" + markdown_table(rows.drop(columns="scene")))
    return "\n".join(parts) if parts else "_(no runs)_\n"
