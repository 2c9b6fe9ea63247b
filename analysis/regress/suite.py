"""make regress: the suite in configs/regression.json, run through psweep, as a measurement frame.

The suite is a list of groups, each a psweep config body (base, sweep, combine, scene_file)
that psweep validates and expands itself; this file only adds what psweep lacks:
- two parts per group: `wall` (psweep's repetitions, warm-up and pinning, on the real machine)
  and `instructions` (the same configurations with the group's `instructions` overrides, e.g.
  a shorter S, each run under valgrind's cachegrind through scripts/psim-cachegrind, which psweep
  takes as its psim);
- a group's `parts`, when only one of them can measure it (waiting threads spin, and what a spin
  counts under valgrind depends on the scheduler: such groups are timed only);
- thread counts relative to the machine: "1.5x" in a group's T is 1.5 times the CPUs this
  process may run on, rounded up, so that "more threads than CPUs" holds on any runner;
- the facts the instruction gate needs in meta.json: ISA flags and the valgrind version.
Errors in the suite file raise SuiteError("<file>: <key path>: ..."), exit status 2.
"""
from __future__ import annotations

import functools
import json
import math
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from analysis.common.csv_out import write_csv
from analysis.common.load import InputError, load_results
from analysis.regress.check import MEASUREMENT_COLUMNS, PARTS, Thresholds

ROOT = Path(__file__).resolve().parents[2]
CACHEGRIND_PSIM = ROOT / "scripts" / "psim-cachegrind"
TIME_METRICS = ("wall_s", "process_s")


@functools.cache
def glibc_tunables() -> str:
    """glibc's choices that differ between x86-64-v3 CPUs, which scripts/psim-cachegrind pins for
    the counted runs (the string lives there, where psweep's simulated counters use it too)."""
    return subprocess.run([str(CACHEGRIND_PSIM), "--glibc-tunables"], capture_output=True,
                          text=True, check=True).stdout.strip()


# The /proc/cpuinfo flags that name instruction-set extensions -march=native (and glibc's
# dispatch) may use; the rest (hypervisor, constant_tsc, ...) do not change the code that runs.
ISA_FLAG = re.compile(r"^(mmx|sse\w*|ssse3|avx\w*|fma\w*|f16c|bmi\d|popcnt|abm|lzcnt|movbe|adx|"
                      r"aes|vaes|pclmulqdq|vpclmulqdq|sha_ni|gfni|amx\w*|xop|tbm|cx16|rdrand|"
                      r"rdseed|clflushopt|clwb|prefetchw|3dnowprefetch|xsave\w*)$")


class SuiteError(Exception):
    """A bad suite file or an unusable build: one line on stderr, exit status 2."""


@dataclass
class Group:
    name: str
    body: dict                       # psweep keys: base, sweep, combine, scene_file, description
    instructions: dict = field(default_factory=dict)  # base overrides for the valgrind part
    time: str = "wall_s"             # psweep column timed: process_s when output is the point
    parts: tuple = PARTS             # the parts that measure it


@dataclass
class Suite:
    file: str
    groups: list[Group]
    wall: dict                       # repetitions, warmup, pin, timeout_s for psweep
    instructions: dict               # repetitions, timeout_s
    thresholds: Thresholds
    base_rounds: int = 6             # make regress BASE=REF: rounds of both builds ...
    base_repetitions: int = 3        # ... each round running every configuration this many times


def _expect(cond: bool, where: str, what: str):
    if not cond:
        raise SuiteError(f"{where}: {what}")


def _positive_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value > 0


def parse_suite(text: str, file: str) -> Suite:
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise SuiteError(f"{file}: line {err.lineno}, column {err.colno}: invalid JSON: "
                         f"{err.msg}") from None
    _expect(isinstance(doc, dict), file, "expected a JSON object")
    known = {"name", "description", "wall", "instructions", "thresholds", "groups", "base"}
    for key in doc:
        _expect(key in known, f"{file}: {key}", f"unknown key (known: {', '.join(sorted(known))})")

    wall = {"repetitions": 5, "warmup": 1, "pin": "close", "timeout_s": 120}
    wall.update(_section(doc, "wall", wall, file))
    _expect(wall["repetitions"] >= 5, f"{file}: wall.repetitions",
            "at least 5 (the U test cannot separate fewer)")
    _expect(wall["pin"] in ("close", "spread", "none"), f"{file}: wall.pin",
            "expected close, spread or none")
    instructions = {"repetitions": 1, "timeout_s": 600}
    instructions.update(_section(doc, "instructions", instructions, file))

    base = {"rounds": 6, "repetitions": 3}
    base.update(_section(doc, "base", base, file))
    _expect(_positive_int(base["rounds"]) and base["rounds"] >= 6, f"{file}: base.rounds",
            "expected an integer of at least 6 (the signed-rank test cannot separate fewer)")

    defaults = Thresholds()
    given = _section(doc, "thresholds", defaults.__dict__, file)
    for key, value in given.items():
        _expect(isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0,
                f"{file}: thresholds.{key}", f"expected a positive number, got {value!r}")
    thresholds = Thresholds(**{**defaults.__dict__, **given})

    groups_json = doc.get("groups")
    _expect(isinstance(groups_json, list) and groups_json, f"{file}: groups",
            "expected a non-empty list of groups")
    groups, names = [], set()
    for i, g in enumerate(groups_json):
        where = f"{file}: groups[{i}]"
        _expect(isinstance(g, dict), where, "expected an object")
        allowed = {"name", "description", "base", "sweep", "combine", "scene_file",
                   "instructions", "time", "parts"}
        for key in g:
            _expect(key in allowed, f"{where}.{key}",
                    f"unknown key (known: {', '.join(sorted(allowed))})")
        name = g.get("name")
        _expect(isinstance(name, str) and re.fullmatch(r"[A-Za-z0-9_-]+", name or "") is not None,
                f"{where}.name", "expected a name of letters, digits, - and _")
        _expect(name not in names, f"{where}.name", f"duplicate group name {name!r}")
        names.add(name)
        _expect(isinstance(g.get("base"), dict), f"{where}.base", "expected an object")
        overrides = g.get("instructions", {})
        _expect(isinstance(overrides, dict), f"{where}.instructions",
                "expected an object of base overrides, e.g. {\"S\": 20}")
        time = g.get("time", "wall_s")
        _expect(time in TIME_METRICS, f"{where}.time", f"expected one of {TIME_METRICS}")
        parts = g.get("parts", list(PARTS))
        _expect(isinstance(parts, list) and parts and set(parts) <= set(PARTS),
                f"{where}.parts", f"expected a non-empty list of {', '.join(PARTS)}")
        _check_relative_threads(g, where)
        body = {k: v for k, v in g.items() if k not in ("name", "instructions", "time", "parts")}
        groups.append(Group(name, body, overrides, time, tuple(p for p in PARTS if p in parts)))
    return Suite(file, groups, wall, instructions, thresholds, base["rounds"],
                 base["repetitions"])


RELATIVE_T = re.compile(r"^(\d+(\.\d+)?)x$")


def _check_relative_threads(group: dict, where: str) -> None:
    for i, t in enumerate(group.get("sweep", {}).get("T", [])):
        if isinstance(t, str):
            match = RELATIVE_T.match(t)
            _expect(match is not None and float(match.group(1)) > 0, f"{where}.sweep.T[{i}]",
                    f"expected a thread count or a multiple of the CPUs such as \"1.5x\", got {t!r}")


def usable_cpus() -> int:
    return len(os.sched_getaffinity(0))


def resolve_threads(body: dict, cpus: int) -> dict:
    """`body` with each "<f>x" of its swept T replaced by ceil(f x cpus)."""
    threads = body.get("sweep", {}).get("T")
    if not threads:
        return body
    resolved = [max(1, math.ceil(float(t[:-1]) * cpus)) if isinstance(t, str) else t
                for t in threads]
    return {**body, "sweep": {**body["sweep"], "T": list(dict.fromkeys(resolved))}}


def _section(doc: dict, key: str, defaults: dict, file: str) -> dict:
    section = doc.get(key, {})
    _expect(isinstance(section, dict), f"{file}: {key}", "expected an object")
    for k, v in section.items():
        _expect(k in defaults, f"{file}: {key}.{k}",
                f"unknown key (known: {', '.join(sorted(defaults))})")
        if isinstance(defaults[k], int) and k != "timeout_s":
            _expect(_positive_int(v) or (k == "warmup" and v == 0), f"{file}: {key}.{k}",
                    f"expected a positive integer, got {v!r}")
        if k == "timeout_s":
            _expect(isinstance(v, (int, float)) and v > 0, f"{file}: {key}.{k}",
                    f"expected a positive number of seconds, got {v!r}")
    return dict(section)


def load_suite(path: str | Path) -> Suite:
    try:
        text = Path(path).read_text()
    except OSError as err:
        raise SuiteError(f"{path}: cannot read: {err.strerror}") from None
    return parse_suite(text, str(path))


def psweep_config(suite: Suite, group: Group, part: str) -> dict:
    """The psweep config of one group and part, its relative thread counts resolved here."""
    config = {"name": group.name, **resolve_threads(group.body, usable_cpus())}
    if part == "instructions":
        config["base"] = {**group.body["base"], **group.instructions}
        # One run each: counts repeat (see instruction_spread), and valgrind is slow.
        config.update(repetitions=suite.instructions["repetitions"], warmup=0, pin="none",
                      timeout_s=suite.instructions["timeout_s"])
    else:
        config.update(suite.wall)
    return config


def cpu_isa_flags() -> list[str]:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                return sorted(f for f in line.split(":", 1)[1].split() if ISA_FLAG.match(f))
    except OSError:
        pass
    return []


def machine_id() -> str | None:
    """This installation's /etc/machine-id: which machine recorded a baseline, where the model
    name and core count cannot tell two VMs apart."""
    try:
        return Path("/etc/machine-id").read_text().strip() or None
    except OSError:
        return None


def valgrind_version() -> str | None:
    try:
        return subprocess.run(["valgrind", "--version"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def commit_date(commit: str | None) -> str | None:
    if not commit:
        return None
    done = subprocess.run(["git", "-C", str(ROOT), "show", "-s", "--format=%cI", commit],
                          capture_output=True, text=True)
    return done.stdout.strip() or None


def label(group: Group, run: pd.Series) -> str:
    """A configuration's name in tables and plots: the group, the engine and the value of every
    other axis the group sweeps (its constant parameters are in the suite file)."""
    parts = [group.name] + ([str(run["engine"])] if run["engine"] != group.name else [])
    for axis in group.body.get("sweep", {}):
        if axis == "engine" or pd.isna(run.get(axis)):
            continue
        value = run[axis]
        parts.append(f"{axis}={int(value) if float(value).is_integer() else value}")
    return " ".join(parts)


def instruction_count(path: Path) -> float | None:
    """Total instructions executed (all threads) from a cachegrind output file."""
    try:
        for line in path.read_text().splitlines():
            if line.startswith("summary:"):
                return float(line.split()[1])
    except OSError:
        return None
    return None


def run_group(psweep: Path, psim: Path, config: dict, folder: Path, part: str) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    config_path = folder.with_suffix(".json")
    config_path.write_text(json.dumps(config, indent=2) + "\n")
    command = [str(psweep), str(config_path), "--out", str(folder)]
    env = dict(os.environ)
    if part == "instructions":
        counts = folder / "counts"
        shutil.rmtree(counts, ignore_errors=True)
        counts.mkdir()
        command += ["--psim", str(CACHEGRIND_PSIM)]
        env.update(REGRESS_PSIM=str(psim), REGRESS_COUNTS=str(counts))
    else:
        command += ["--psim", str(psim)]
    print(f"regress: {part}: {config['name']}", file=sys.stderr, flush=True)
    status = subprocess.run(command, env=env).returncode
    if status == 2:
        raise SuiteError(f"psweep rejected the config of group {config['name']!r} "
                         f"(written to {config_path}): see its message above")
    if status != 0:
        raise SuiteError(f"psweep {config_path} failed with exit status {status}")


def collect(group: Group, folder: Path, part: str) -> pd.DataFrame:
    """psweep's runs.csv of one group and part as measurement rows."""
    try:
        runs = load_results(folder).runs
    except InputError as err:
        raise SuiteError(str(err)) from None
    rows = []
    for _, run in runs.iterrows():
        if part == "instructions":
            metric = "instructions"
            # psweep names each run's metrics file <config_id>-<rep>.json; the wrapper names
            # its count after it.
            value = instruction_count(folder / "counts" / f"{run['config_id']}-{int(run['rep'])}.cg")
            status = run["status"] if value is not None or run["status"] != "ok" else "no count"
        else:
            metric, value, status = group.time, run[group.time], run["status"]
        rows.append({"part": part, "group": group.name, "config_id": run["config_id"],
                     "label": label(group, run), "engine": run["engine"],
                     "engine_ran": run.get("engine_ran"), "T": run["T"], "rep": int(run["rep"]),
                     "status": status, "metric": metric, "value": value,
                     "state_hash": run.get("state_hash"), "error": run.get("error")})
    return pd.DataFrame(rows, columns=MEASUREMENT_COLUMNS)


def check_build(build: Path, parts=PARTS) -> tuple[Path, Path]:
    psim, psweep = build / "psim", build / "psweep"
    for exe in (psim, psweep):
        if not os.access(exe, os.X_OK):
            raise SuiteError(f"{exe} not found: build first (make build BUILD={build})")
    # valgrind 3.19 cannot decode AVX-512: such a psim dies with SIGILL before main, so every
    # count would come back a failed run instead of a number.
    if "instructions" in parts and uses_avx512(build) and "avx512f" in cpu_isa_flags():
        raise SuiteError(f"{build} uses AVX-512, which valgrind cannot run: count a build without "
                         f"it (make regress makes build-regress; or make build BUILD=DIR AVX512=0)")
    return psim, psweep


def uses_avx512(build: Path) -> bool:
    """Whether the CMake build in `build` lets -march=native use AVX-512 (PARTICLE_AVX512)."""
    cache = build / "CMakeCache.txt"
    return cache.exists() and re.search(r"^PARTICLE_AVX512:BOOL=(ON|1|TRUE|YES)$",
                                        cache.read_text(), flags=re.M | re.I) is not None


def measure(suite: Suite, build: Path, out: Path, parts=PARTS,
            instruction_reps: int | None = None) -> tuple[pd.DataFrame, dict]:
    """Runs the suite's `parts` with the binaries in `build`; writes psweep's folders under
    out/<part>/<group>/, then out/measurements.csv and out/meta.json, and returns both."""
    psim, psweep = check_build(build, parts)
    if "instructions" in parts and valgrind_version() is None:
        raise SuiteError("valgrind not found: the instruction counts need it "
                         "(scripts/bootstrap.sh installs it)")
    if instruction_reps:
        suite.instructions["repetitions"] = instruction_reps
    shutil.rmtree(out, ignore_errors=True)
    frames, psweep_meta = [], {}
    for part in parts:
        for group in (g for g in suite.groups if part in g.parts):
            folder = out / part / group.name
            run_group(psweep, psim, psweep_config(suite, group, part), folder, part)
            frames.append(collect(group, folder, part))
            if not psweep_meta:
                psweep_meta = json.loads((folder / "meta.json").read_text())
    measurements = pd.concat(frames, ignore_index=True)
    meta = {key: psweep_meta.get(key) for key in ("date", "git", "build", "machine", "openmp")}
    meta["git"]["commit_date"] = commit_date(meta["git"].get("commit"))
    meta["machine"]["isa_flags"] = cpu_isa_flags()
    meta["machine"]["machine_id"] = machine_id()
    meta["valgrind"] = valgrind_version() if "instructions" in parts else None
    meta["glibc_tunables"] = glibc_tunables() if "instructions" in parts else None
    meta["parts"] = list(parts)
    meta["suite_file"] = suite.file
    meta["thresholds"] = suite.thresholds.__dict__
    write_csv(measurements, out / "measurements.csv")
    (out / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")
    return measurements, meta


def read_measurements(folder: Path) -> tuple[pd.DataFrame, dict]:
    """A recorded run or baseline: measurements.csv and meta.json."""
    try:
        frame = pd.read_csv(folder / "measurements.csv",
                            dtype={"config_id": str, "state_hash": str, "label": str})
        meta = json.loads((folder / "meta.json").read_text())
    except FileNotFoundError as err:
        raise SuiteError(f"{err.filename} not found") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, json.JSONDecodeError) as err:
        raise SuiteError(f"{folder}: unreadable: {err}") from None
    missing = [c for c in MEASUREMENT_COLUMNS if c not in frame.columns]
    if missing:
        raise SuiteError(f"{folder / 'measurements.csv'} lacks the column(s) {', '.join(missing)}")
    return frame, meta
