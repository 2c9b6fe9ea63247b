"""How long the timing sweep will take, from each submission's own judging runs: psweep's cost
model prices every program as the lab's plain all-pairs one, and a slow student program (30 to 40
minutes where 5 were estimated) is not that.

A submission's run on a scene takes about `start + per_work x N^2 S K`: `start` its quickest
judging run (a scene of a few particles: the process, the sandbox, the input), `per_work` what
its runs on the largest judging scene took beyond that, per unit of all-pairs work (N^2 pairs,
S K sub-steps: the assignment's method; a program with a broad phase is overestimated, the safe
side). Each T is estimated from the judging runs at that T, each run capped at the timing's
timeout, and a T no judging run had takes the estimate of the smallest that did.
"""
from __future__ import annotations

import pandas as pd


def _work(rows: pd.DataFrame | pd.Series) -> pd.Series | float:
    """All-pairs work of a run's scene: N^2 x S x K."""
    k = rows["slow_factor"].fillna(1) if isinstance(rows, pd.DataFrame) else (
        1 if pd.isna(rows["slow_factor"]) else rows["slow_factor"])
    return rows["N"] ** 2 * rows["S"] * k


def run_estimate_s(runs: pd.DataFrame, scene: dict) -> float | None:
    """One run on the timing `scene` (N, S, slow_factor) from one program's ok judging runs at
    one T; None without any."""
    if runs.empty:
        return None
    work = _work(runs)
    start = float(runs["process_s"].min())
    largest = runs[work == work.max()]
    per_work = max(0.0, float(largest["process_s"].min()) - start) / float(work.max())
    timing_work = scene.get("N", 1000) ** 2 * scene.get("S", 1000) * scene.get("slow_factor", 1)
    return start + per_work * timing_work


def timing_estimates_s(judging: pd.DataFrame, programs: list[str], scene: dict,
                       threads: list[int], runs_per_T: int, timeout_s: float) -> dict[str, float]:
    """Each program's seconds in the timing sweep: `runs_per_T` runs (repetitions, warm-up and
    the judging run of the timing scene) at each T of `threads`, from `judging`, the judging
    sweeps' runs together."""
    ok = judging[(judging["status"] == "ok") & judging["process_s"].notna()]
    estimates = {}
    for name in programs:
        mine = ok[ok["engine"] == name]
        per_T = {t: run_estimate_s(mine[mine["T"] == t], scene) for t in sorted(mine["T"].unique())}
        known = [s for s in per_T.values() if s is not None]
        if not known:
            continue
        estimates[name] = sum(runs_per_T * min(timeout_s, per_T.get(t) or known[0])
                              for t in threads)
    return estimates
