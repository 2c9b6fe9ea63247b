"""What a grading runs: the submissions of a folder, the grade config (configs/grade.json), and the
psweep configs made from the two, one per judging scene and one for timing. psweep runs them:
the timing, the judging and the failures of a submission are psweep's, not redone here.

Convention for a submission: every regular file of the folder whose name does not start with
'.' is one, named by its file name (the scoreboard's row, psweep's program name), and is run as
`DIR/NAME < scene` with OMP_NUM_THREADS = T (psweep sets it, with the pinning). No argument: the
thread count an OpenMP program reads without code, and a submission that needs arguments (mpirun,
its own flags) is a two-line shell script in the folder.
"""
from __future__ import annotations

import json
import subprocess
from dataclasses import dataclass
from pathlib import Path

from analysis.common.load import InputError

CONFIG_KEYS = {"description", "judging", "timing", "pin"}
JUDGING_KEYS = {"scenes", "T", "timeout_s"}
TIMING_KEYS = {"scene", "T", "engines", "repetitions", "warmup", "timeout_s"}


@dataclass
class JudgingScene:
    file: str     # as psweep's scene_file: relative to the repository root
    tests: str    # what it tests, for the reports

    @property
    def name(self) -> str:
        return Path(self.file).stem


@dataclass
class GradeConfig:
    path: Path
    scenes: list[JudgingScene]
    judging: dict
    timing: dict
    pin: str


def find_submissions(folder: str | Path) -> dict[str, Path]:
    """Name -> path of every submission in `folder`, sorted by name."""
    folder = Path(folder)
    if not folder.exists():
        raise InputError(f"submissions folder {folder} does not exist")
    if not folder.is_dir():
        raise InputError(f"{folder} is not a folder (expected a folder of submissions, "
                         "one executable each)")
    found = {p.name: p for p in sorted(folder.iterdir())
             if p.is_file() and not p.name.startswith(".")}
    if not found:
        raise InputError(f"{folder} holds no submission (each regular file whose name does not "
                         "start with '.' is one)")
    return found


def _keys(section: dict, allowed: set[str], where: str) -> None:
    unknown = sorted(set(section) - allowed)
    if unknown:
        raise InputError(f"{where}.{unknown[0]}: unknown key (expected one of "
                         f"{', '.join(sorted(allowed))})")


def _section(raw: dict, key: str, allowed: set[str], path: Path) -> dict:
    section = raw.get(key)
    if not isinstance(section, dict):
        raise InputError(f"{path}: {key}: expected an object")
    _keys(section, allowed, f"{path}: {key}")
    return section


def read_config(path: str | Path) -> GradeConfig:
    """The grade config, its shape checked here; the values psweep checks (T, timeouts, the
    timing scene) are reported by psweep at the generated config's key path."""
    path = Path(path)
    try:
        raw = json.loads(path.read_text())
    except OSError as err:
        raise InputError(f"cannot read the grade config {path}: {err.strerror}") from None
    except json.JSONDecodeError as err:
        raise InputError(f"{path}: line {err.lineno}, column {err.colno}: invalid JSON: "
                         f"{err.msg}") from None
    if not isinstance(raw, dict):
        raise InputError(f"{path}: expected a JSON object")
    _keys(raw, CONFIG_KEYS, str(path))
    judging = _section(raw, "judging", JUDGING_KEYS, path)
    timing = _section(raw, "timing", TIMING_KEYS, path)
    entries = judging.get("scenes")
    if not isinstance(entries, list) or not entries:
        raise InputError(f"{path}: judging.scenes: expected a non-empty list of "
                         '{"file": ..., "tests": ...}')
    scenes = []
    for i, entry in enumerate(entries):
        where = f"{path}: judging.scenes[{i}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("file"), str):
            raise InputError(f'{where}: expected {{"file": "scenes/x.in", "tests": "..."}}')
        _keys(entry, {"file", "tests"}, where)
        scene = JudgingScene(entry["file"], str(entry.get("tests", "")))
        if not Path(scene.file).is_file():
            raise InputError(f"{where}.file: {scene.file} not found (paths are relative to the "
                             "repository root)")
        if any(s.name == scene.name for s in scenes):
            raise InputError(f"{where}.file: a second scene named {scene.name} (each scene's "
                             "results go to judge/<file name without .in>)")
        scenes.append(scene)
    if not isinstance(timing.get("scene"), dict):
        raise InputError(f"{path}: timing.scene: expected an object of psweep base keys "
                         '({"N": 1000, "L": 20000, "r": 1, "S": 1000, "seed": 3210})')
    return GradeConfig(path=path, scenes=scenes, judging=judging, timing=timing,
                       pin=raw.get("pin", "close"))


def programs(submissions: dict[str, Path]) -> dict:
    """psweep's `programs` key: each submission as the convention above runs it."""
    return {name: {"command": [str(path.resolve())], "input": "stdin", "uses": ["T"]}
            for name, path in submissions.items()}


def judging_config(config: GradeConfig, scene: JudgingScene, submissions: dict[str, Path]) -> dict:
    """One judging scene: every submission once per T (psim check judges each T's output)."""
    names = list(submissions)
    return {
        "name": f"judge-{scene.name}",
        "description": f"make grade: {scene.tests}",
        "scene_file": scene.file,
        "base": {"engine": names[0], "T": 1},
        "sweep": {"engine": names, "T": config.judging.get("T", [1])},
        "programs": programs(submissions),
        "repetitions": 1, "warmup": 0, "pin": config.pin,
        "timeout_s": config.judging.get("timeout_s", 30),
    }


def timing_config(config: GradeConfig, submissions: dict[str, Path]) -> dict:
    timing = config.timing
    settings = {
        "name": "timing",
        "description": "make grade: the submissions timed beside psim's engines",
        "base": {"engine": "brute", "T": 1, **timing["scene"]},
        "sweep": {"engine": list(timing.get("engines", [])) + list(submissions),
                  "T": timing.get("T", [1])},
        "repetitions": timing.get("repetitions", 3), "warmup": timing.get("warmup", 1),
        "pin": config.pin, "timeout_s": timing.get("timeout_s", 600),
    }
    if submissions:
        settings["programs"] = programs(submissions)
    return settings


class SweepError(Exception):
    """psweep did not complete a sweep; `status` is the exit status grade passes on."""

    def __init__(self, message: str, status: int):
        super().__init__(message)
        self.status = status


def run_sweep(psweep: str, settings: dict, config_path: Path, out: Path) -> None:
    """Writes the config (kept beside the results: the command to rerun one sweep) and runs
    psweep on it; its progress and its verdicts go to the terminal as they come."""
    config_path.parent.mkdir(parents=True, exist_ok=True)
    config_path.write_text(json.dumps(settings, indent=2) + "\n")
    try:
        done = subprocess.run([psweep, str(config_path), "--out", str(out), "--yes"])
    except OSError as err:
        raise SweepError(f"cannot run psweep {psweep}: {err.strerror} (make build first, or "
                         "--psweep PATH)", 2) from None
    if done.returncode == 2:
        raise SweepError(f"psweep refused {config_path} (its message above; the program names "
                         "are the submissions' file names)", 2)
    if done.returncode != 0:
        raise SweepError(f"psweep stopped with exit status {done.returncode} on {config_path}",
                         1 if done.returncode < 128 else done.returncode)
