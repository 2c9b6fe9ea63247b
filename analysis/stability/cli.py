"""`make stability`: every scene of scenes.py through every engine psim knows.

    /usr/bin/python3 -m analysis stability [--psim build/psim] [--out results/stability] [--quick]
        [--timeout S]

Checks per run: exit 0 (or, for a scene the doubles cannot represent, exit 2 naming the reason);
no NaN or infinity in the output or the metrics; final positions in [r, L-r]; the energy drift
within the scene's bound (scenes.drift_bound); no hang (a timeout per run); the engines
psim's declaration (`psim --describe`) says match the reference engine bit-identical to it
(state_hash). Writes OUT/stability.csv and OUT/report.md (failures
first) and exits 1 if any run fails, 2 on bad usage.

Everything but main() and run_psim() is a pure function of its arguments.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import pandas as pd

from analysis.common import psim as psim_runner
from analysis.common.csv_out import write_csv
from analysis.common.declaration import Declaration
from analysis.stability.scenes import Scene, drift_bound, scenes

PRINT_TOLERANCE = 5e-9  # %.8f rounds to the nearest 1e-8


@dataclass
class Outcome:
    """What one psim process did."""
    returncode: int | None  # None: killed by the timeout
    stdout: str
    stderr: str
    metrics: dict | None
    seconds: float


@dataclass
class Row:
    scene: str
    engine: str
    status: str  # ok, refused (as expected), fail
    reason: str
    drift: float
    drift_bound: float
    max_overlap: float
    nan_count: int
    out_of_box: int
    time_s: float
    state_hash: str


def non_finite(value) -> int:
    """How many numbers in a JSON value are null, NaN or infinite (null is how a NaN arrives)."""
    if value is None:
        return 1
    if isinstance(value, float):
        return 0 if math.isfinite(value) else 1
    if isinstance(value, dict):
        return sum(non_finite(v) for v in value.values())
    if isinstance(value, list):
        return sum(non_finite(v) for v in value)
    return 0


def parse_state(stdout: str, n: int) -> tuple[list[list[float]], int]:
    """The final state (the last n lines) as [x, y, vx, vy] rows, and the count of tokens in
    the whole output that are not finite numbers."""
    bad = 0
    lines = stdout.splitlines()
    for line in lines:
        for token in line.split():
            try:
                bad += not math.isfinite(float(token))
            except ValueError:
                bad += 1
    final = []
    for line in lines[-n:] if n else []:
        fields = line.split()
        try:
            final.append([float(v) for v in fields[2:6]])
        except (ValueError, IndexError):
            pass
    return final, bad


def outside_box(state: list[list[float]], L: float, r: float) -> int:
    """Particles whose printed position is outside [r, L-r] by more than the printing error."""
    lo, hi = r - PRINT_TOLERANCE, (L - r) + PRINT_TOLERANCE
    return sum(not (lo <= x <= hi and lo <= y <= hi) for x, y, *_ in state)


def energy_drift(metrics: dict) -> float:
    """psim's energy_drift when it reports it, else from the energies (0 for a scene at rest)."""
    if "energy_drift" in metrics:
        value = metrics["energy_drift"]
        return math.nan if value is None else float(value)
    e0, e1 = metrics.get("energy_initial"), metrics.get("energy_final")
    if e0 is None or e1 is None:
        return math.nan
    if e0 == 0:
        return 0.0 if e1 == 0 else math.inf
    return (e1 - e0) / e0


def max_overlap(metrics: dict, state: list[list[float]], r: float) -> float:
    """psim's max_overlap (deepest overlap at a step end, relative to s) when it reports it;
    else the final printed state's deepest overlap (small scenes only: O(N^2))."""
    if "max_overlap" in metrics:
        value = metrics["max_overlap"]
        return math.nan if value is None else float(value)
    s, deepest = 2 * r, 0.0
    if len(state) > 400 or s < 1e-6:  # too slow, or below what %.8f resolves
        return math.nan
    for i, a in enumerate(state):
        for b in state[i + 1:]:
            deepest = max(deepest, (s - math.hypot(a[0] - b[0], a[1] - b[1])) / s)
    return deepest


def check(scene: Scene, engine: str, out: Outcome) -> Row:
    """One run of `engine` against the scene's expectations (the reference's hash is compared
    later)."""
    row = Row(scene.name, engine, "fail", "", math.nan, math.nan, math.nan, 0, 0,
              round(out.seconds, 3), "")
    first_error = out.stderr.strip().splitlines()[-1] if out.stderr.strip() else ""
    if out.returncode is None:
        row.reason = "timeout"
        return row
    refuse = scene.refusal(engine)
    if refuse:
        if out.returncode == 2 and refuse in out.stderr.lower():
            row.status, row.reason = "refused", first_error
        else:
            row.reason = (f"expected exit 2 naming '{refuse}', got exit {out.returncode}"
                          + (f": {first_error}" if first_error else ""))
        return row
    may_refuse = scene.may_refuse_by.get(engine, "")
    if may_refuse and out.returncode == 2 and may_refuse in out.stderr.lower():
        row.status, row.reason = "refused", first_error
        return row
    if out.returncode != 0:
        row.reason = f"exit {out.returncode}: {first_error}"
        return row
    metrics = out.metrics or {}
    n = len(scene.particles) if scene.particles is not None else scene.N
    state, bad = parse_state(out.stdout, n)
    row.nan_count = bad + non_finite(metrics)
    row.out_of_box = outside_box(state, scene.L, scene.r)
    row.drift = energy_drift(metrics)
    pair_collisions = int(metrics.get("counters", {}).get("pair_collisions", 0))
    row.drift_bound = drift_bound(pair_collisions)
    row.max_overlap = max_overlap(metrics, state, scene.r)
    row.state_hash = str(metrics.get("state_hash", ""))
    problems = []
    if not metrics:
        problems.append("no metrics")
    if len(state) != n:
        problems.append(f"{len(state)} final lines for N={n}")
    if row.nan_count:
        problems.append(f"{row.nan_count} non-finite values")
    if row.out_of_box:
        problems.append(f"{row.out_of_box} particles outside [r, L-r]")
    if not abs(row.drift) <= row.drift_bound:
        problems.append(f"energy drift {row.drift:.3g} beyond {row.drift_bound:.3g}")
    row.status = "fail" if problems else "ok"
    row.reason = "; ".join(problems)
    return row


def compare_with_reference(rows: list[Row], declaration: Declaration) -> None:
    """Marks the engines declared to match the reference whose state_hash differs from the
    reference engine's on the same scene."""
    exact = declaration.exact_engines or set()
    name = declaration.reference
    reference = {r.scene: r.state_hash for r in rows if r.engine == name and r.status == "ok"}
    for row in rows:
        ref = reference.get(row.scene)
        if row.status == "ok" and row.engine in exact and ref and row.state_hash != ref:
            row.status = "fail"
            row.reason = f"state_hash {row.state_hash} differs from {name}'s {ref}"


def ordered(rows: list[Row]) -> list[Row]:
    """Failures first, then by scene and engine."""
    return sorted(rows, key=lambda r: (r.status != "fail", r.scene, r.engine))


def fmt(value: float) -> str:
    return "" if isinstance(value, float) and math.isnan(value) else f"{value:.3g}"


def report_markdown(rows: list[Row], scene_list: list[Scene],
                    skipped: dict[str, str] | None = None) -> str:
    failed = [r for r in rows if r.status == "fail"]
    lines = ["# Stability report", "",
             f"{len(rows)} runs, {len(failed)} failed, "
             f"{sum(r.status == 'refused' for r in rows)} refused as expected.", ""]
    for name, why in (skipped or {}).items():
        lines += [f"Engine `{name}` not run: {why}.", ""]
    lines += ["| scene | engine | status | drift | bound | max overlap | NaN | outside | time s "
              "| reason |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in ordered(rows):
        lines.append(f"| {r.scene} | {r.engine} | {r.status} | {fmt(r.drift)} | "
                     f"{fmt(r.drift_bound)} | {fmt(r.max_overlap)} | {r.nan_count} | "
                     f"{r.out_of_box} | {r.time_s:.3f} | {r.reason.replace('|', '/')} |")
    lines += ["", "## Scenes", ""]
    lines += [f"- `{s.name}`: {s.about}" for s in scene_list]
    lines += ["", "Drift bound: max(1e-10, 8 eps x pair collisions): only pair exchanges "
              "change the energy, each by at most about 8 ulps of the pair's energy.", ""]
    return "\n".join(lines)


def rows_table(rows: list[Row]) -> pd.DataFrame:
    return pd.DataFrame([asdict(r) for r in ordered(rows)], columns=[f.name for f in fields(Row)])


def run_psim(psim: Path, scene_file: Path, engine: str, options: list[str], metrics: Path,
             timeout: float) -> Outcome:
    metrics.unlink(missing_ok=True)
    done = psim_runner.run(psim, ["--engine", engine, "--threads", 1, "--metrics", metrics,
                                  *options, scene_file], timeout=timeout)
    if done.returncode is None:
        return Outcome(None, "", "", None, done.seconds)
    try:
        parsed = json.loads(metrics.read_text()) if metrics.exists() else None
    except json.JSONDecodeError:
        parsed = None
    return Outcome(done.returncode, done.stdout, done.stderr, parsed, done.seconds)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--psim", type=Path, default=Path("build/psim"))
    ap.add_argument("--out", type=Path, default=Path("results/stability"))
    ap.add_argument("--quick", action="store_true", help="only the quick subset (make test)")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per run")
    args = ap.parse_args(argv)
    if not args.psim.is_file():
        print(f"stability: {args.psim}: no such program (run make build)", file=sys.stderr)
        return 2
    try:
        declaration = psim_runner.describe(args.psim)
    except psim_runner.PsimError as err:
        print(f"stability: {err}", file=sys.stderr)
        return 2
    scene_list = [s for s in scenes() if s.quick or not args.quick]
    # An engine this psim cannot run here (gpu without a device) is said, not silently left out.
    skipped = {e["name"]: e["unavailable"] for e in declaration.engines if e.get("unavailable")}
    for name, why in skipped.items():
        print(f"stability: engine {name} not run: {why}", file=sys.stderr)
    (args.out / "scenes").mkdir(parents=True, exist_ok=True)
    metrics = args.out / "metrics.json"
    rows = []
    for scene in scene_list:
        path = args.out / "scenes" / f"{scene.name}.in"
        path.write_text(scene.text())
        for engine in (e["name"] for e in declaration.engines if e["name"] not in skipped):
            out = run_psim(args.psim, path, engine, scene.options, metrics, args.timeout)
            rows.append(check(scene, engine, out))
            print(f"stability: {scene.name} {engine}: {rows[-1].status} "
                  f"{rows[-1].reason}", file=sys.stderr)
    metrics.unlink(missing_ok=True)
    compare_with_reference(rows, declaration)
    write_csv(rows_table(rows), args.out / "stability.csv")
    (args.out / "report.md").write_text(report_markdown(rows, scene_list, skipped))
    failed = [r for r in rows if r.status == "fail"]
    print(f"stability: {len(rows)} runs, {len(failed)} failed; {args.out}/report.md",
          file=sys.stderr)
    return 1 if failed else 0

