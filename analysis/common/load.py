"""Read a psweep results folder (docs/sweeps.md, "Output files") into DataFrames.

All validation of the input happens here, once: anything a user can get wrong (missing folder,
empty or truncated CSV, missing columns, no thread-count baseline) raises InputError with a
message that names the file and the problem; the command line turns it into exit status 2.
Everything downstream may assume a clean `runs` frame.
"""
from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from analysis.common import advice
from analysis.common.declaration import Declaration


class InputError(Exception):
    """Bad user input: reported as one line on stderr, exit status 2."""


# Parameters that identify a configuration apart from the thread count T. Two runs with equal
# values here and the same T are repetitions of one configuration. G is empty for every engine
# that does not use it, speed_min/max are empty for scene files: groupbys over these must keep NaN keys.
# A run beside a busy neighbour is a different experiment, not a slower repetition of a quiet one.
# P (MPI ranks) is empty for every engine that does not run on ranks.
CONFIG_PARAMS = ["engine", "N", "L", "r", "S", "slow_factor", "P", "G", "seed",
                 "speed_min", "speed_max", "scene_file", "pin", "neighbour", "wall_stop",
                 "overlap"]

# The scene (what is simulated) apart from how it is simulated (engine, G, T, pin): runs of the
# same scene must agree on the final state hash, and the declared reference engine (brute) at
# T=1 on the same scene is the sequential reference for speedup_vs_brute.
# The readings are part of the model (docs/model.md, "Readings"): another reading is another
# simulation, whose hash differs.
SCENE_PARAMS = ["N", "L", "r", "S", "slow_factor", "seed", "speed_min", "speed_max", "scene_file",
                "wall_stop", "overlap"]
# Each reading's column and its default: that of sweeps older than the column, and of every row
# where it does not apply.
DEFAULT_READINGS = {"wall_stop": "per-coordinate", "overlap": "approaching"}

# Without these nothing can be computed; the rest of the harness's columns are optional.
REQUIRED_COLUMNS = ["engine", "N", "T", "status", "wall_s"]

# psweep's own numeric columns (parameters and what it measures about each child). The
# metric columns psim reports come from the declaration in meta.json (declaration.py).
NUMERIC_COLUMNS = [
    "N", "L", "r", "S", "slow_factor", "T", "P", "G", "speed_min", "speed_max", "rep",
    "exit_code", "wall_s", "process_s", "user_s", "sys_s", "max_rss_kb",
    "voluntary_switches", "involuntary_switches", "context_switches", "cpu_migrations",
    "page_faults", "task_clock_s", "cycles", "instructions", "branches", "branch_misses",
    "cache_misses", "oversubscribed", "busy_tasks", "check_first_step",
]

# Identities and messages: never numbers (seed is a 64-bit identity that a float would round; a
# node may be named 001).
TEXT_COLUMNS = ["seed", "scene_file", "pin", "neighbour", "wall_stop", "overlap", "engine_ran", "node",
                "state_hash", "cpus", "error", "check", "check_detail", "counters_source"]
# An external program's check (docs/programs.md): empty on engines' rows, absent from older sweeps.
CHECK_COLUMNS = ["check", "check_detail"]

KEY_NUMERIC_COLUMNS = ["N", "L", "r", "S", "slow_factor", "T", "P", "G", "speed_min",
                       "speed_max", "wall_s"]


@dataclass
class Results:
    """One sweep: every repetition as a row, plus the sweep's provenance."""
    directory: Path
    runs: pd.DataFrame          # all rows, any status; numeric columns are floats (NaN = empty)
    meta: dict = field(default_factory=dict)

    @property
    def declaration(self) -> Declaration:
        return Declaration.from_meta(self.meta)

    @property
    def ok(self) -> pd.DataFrame:
        return self.runs[self.runs["status"] == "ok"]

    @property
    def programs(self) -> set[str]:
        """The external programs the sweep ran beside the engines (meta.json's programs)."""
        programs = self.meta.get("programs")
        return set(programs) if isinstance(programs, dict) else set()

    @property
    def cores(self) -> int | None:
        """CPUs the OpenMP runtime can use: beyond this T is oversubscribed (the harness's
        own rule). psweep writes machine.online_cpus; a flat `cores` key is accepted too."""
        machine = self.meta.get("machine") if isinstance(self.meta.get("machine"), dict) else {}
        for value in (self.meta.get("cores"), machine.get("online_cpus"),
                      machine.get("physical_cores")):
            try:
                if value is not None and int(value) > 0:
                    return int(value)
            except (TypeError, ValueError):
                continue
        return None


def load_results(directory: str | Path) -> Results:
    directory = Path(directory)
    if not directory.exists():
        raise InputError(f"results folder {directory} does not exist")
    if not directory.is_dir():
        raise InputError(f"{directory} is not a folder (expected a psweep results folder)")
    runs_path = directory / "runs.csv"
    if not runs_path.exists():
        raise InputError(f"{runs_path} not found: is {directory} a psweep results folder?")
    meta = read_meta(directory / "meta.json")
    runs = read_runs(runs_path, Declaration.from_meta(meta))
    return Results(directory=directory, runs=runs, meta=meta)


def read_runs(path: Path, declaration: Declaration | None = None) -> pd.DataFrame:
    try:
        # Everything as text first, so a stray word in a numeric column is reported by name
        # instead of silently turning the column into strings.
        runs = pd.read_csv(path, dtype=str, keep_default_na=False)
    except pd.errors.EmptyDataError:
        raise InputError(f"{path} is empty (no header): did the sweep run at all?") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as err:
        raise InputError(f"{path} is not a valid CSV file: {err}") from None
    runs.columns = [c.strip() for c in runs.columns]
    missing = [c for c in REQUIRED_COLUMNS if c not in runs.columns]
    if missing:
        raise InputError(f"{path} lacks the column(s) {', '.join(missing)} "
                         f"(has: {', '.join(runs.columns)})")
    if runs.empty:
        raise InputError(f"{path} has a header but no runs: did the sweep run at all?")
    return normalise(runs, path, declaration)


def normalise(runs: pd.DataFrame, path: Path | str = "runs.csv",
              declaration: Declaration | None = None) -> pd.DataFrame:
    """Typed columns: numbers as float (NaN for empty cells), text stripped, optional columns
    present (as NaN) so later code need not test for them. Every metric psim declares is a
    number (a flag reads 1/0)."""
    runs = runs.copy()
    numeric = NUMERIC_COLUMNS + (declaration or Declaration()).metric_columns()
    for column in CONFIG_PARAMS + numeric + CHECK_COLUMNS:
        if column not in runs.columns:
            runs[column] = float("nan")
    runs["engine"] = runs["engine"].astype(str).str.strip()
    runs["status"] = runs["status"].astype(str).str.strip()
    for column in TEXT_COLUMNS:
        if column in runs.columns:
            text = runs[column].astype(str).str.strip()
            runs[column] = text.where((text != "") & (text != "nan"))
    for column, default in DEFAULT_READINGS.items():
        runs[column] = runs[column].fillna(default)
    # A column nobody declared (results without meta.json, or from an older psim) is a number
    # when every non-empty cell reads as one.
    for column in runs.columns.difference(TEXT_COLUMNS + ["config_id", "engine", "status"]
                                          + numeric):
        text = runs[column].astype(str).str.strip()
        empty = (text == "") | (text == "nan") | runs[column].isna()
        values = pd.to_numeric(text.where(~empty), errors="coerce")
        if not (values.isna() & ~empty).any():
            runs[column] = values.astype(float)
    for column in numeric:
        text = runs[column].astype(str).str.strip()
        empty = (text == "") | (text == "nan") | runs[column].isna()
        values = pd.to_numeric(text.where(~empty), errors="coerce")
        bad = values.isna() & ~empty
        if bad.any():
            row = int(bad.idxmax())
            where = f"{path}: column {column}, data row {row + 1}: {text[row]!r} is not a number"
            # A garbled parameter or wall time would silently regroup or drop runs; a garbled
            # auxiliary counter only loses that counter's plot, so it is a warning.
            if column in KEY_NUMERIC_COLUMNS:
                raise InputError(where)
            print(f"plots: warning: {where}; treated as empty", file=sys.stderr)
        runs[column] = values.astype(float)
    ok = runs["status"] == "ok"
    for column in ["N", "wall_s"]:
        if runs.loc[ok, column].isna().any():
            row = int((ok & runs[column].isna()).idxmax())
            raise InputError(f"{path}: column {column}, data row {row + 1}: empty in an ok run")
    # Engines that ignore threads (their declaration does not use T) leave T empty: they ran on
    # one thread.
    runs["T"] = runs["T"].fillna(1.0)
    return runs


def read_meta(path: Path) -> dict:
    """meta.json is provenance, not data: a missing file only loses the report's header and the
    core-count marker; a malformed one is an error because it means a broken results folder."""
    if not path.exists():
        return {}
    try:
        meta = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"{path} is not valid JSON: {err}") from None
    if not isinstance(meta, dict):
        raise InputError(f"{path}: expected a JSON object, found {type(meta).__name__}")
    return meta


def status_counts(runs: pd.DataFrame) -> dict[str, int]:
    return {str(k): int(v) for k, v in runs["status"].value_counts().sort_index().items()}


def require_usable(results: Results) -> None:
    """The checks that need the whole sweep: some ok run, and a T=1 baseline somewhere."""
    ok = results.ok
    if ok.empty:
        counts = status_counts(results.runs)
        how = " and ".join(f"{n} {status}" for status, n in counts.items())
        errors = (results.runs["error"].dropna().astype(str).str.strip()
                  if "error" in results.runs.columns else pd.Series(dtype=str))
        errors = errors[errors != ""]
        why = f" (first error: {errors.iloc[0]})" if len(errors) else ""
        raise InputError(f"{results.directory / 'runs.csv'} has no successful run, so there is "
                         f"nothing to plot: {how}{why}")
    if not (ok["T"] == 1).any():
        ts = sorted(int(t) for t in ok["T"].unique())
        raise InputError(f"{results.directory / 'runs.csv'} has no successful run at T=1, so "
                         f"there is no baseline for speed-up (thread counts present: {ts}); "
                         f"add 1 to {advice.SWEEP_T}")
