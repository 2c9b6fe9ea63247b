"""What a grading runs: the submissions of a folder, the grade config (configs/grade.json), and the
psweep configs made from the two, one per judging scene and one for timing. psweep runs them:
the timing, the judging and the failures of a submission are psweep's, not redone here.

Convention for a submission: every entry of the folder whose name does not start with '.' is
one, named by its file name (the scoreboard's row, shown escaped), and is run as `NAME < scene`
with OMP_NUM_THREADS = T, confined (psweep sets it, with the pinning and the sandbox). No
argument: the thread count an OpenMP program reads without code, and a submission that needs
arguments (mpirun, its own flags) is a two-line shell script in the folder. A folder, a special
file or a symlink that leads out of the folder gets its row saying so and is not run.
"""
from __future__ import annotations

import json
import os
import re
import secrets
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from analysis.common.load import InputError
from analysis.grade.board import is_board_column
from analysis.grade.curve import Quiet, SpeedCurve, read_curve, read_quiet
from analysis.grade.families import FAMILIES
from analysis.grade.gradescope import DEFAULT_POINTS

CONFIG_KEYS = {"description", "judging", "timing", "pin", "points", "reading", "overlap_reading",
               "submission"}
# How every submission is run (the course's interface): its arguments after the program (psweep's
# placeholders, "{T}" the thread count), its environment, the sub-steps K it is built for and how
# its output numbers them ("numbers": "sub-steps", as the 2019 authors' parallel-2 prints every
# sub-step); and how a folder of sources is built (build.py): the command, its time, the program.
SUBMISSION_KEYS = {"args", "env", "slow_factor", "numbers", "build", "build_timeout_s", "program"}
# The readings a grade config may require (docs/model.md, "Readings"), by key, as psweep's.
READINGS = {"reading": ("per-coordinate", "whole-motion"),
            "overlap_reading": ("approaching", "always")}
JUDGING_KEYS = {"scenes", "T", "timeout_s", "seed"}
TIMING_KEYS = {"scene", "T", "engines", "stretch", "repetitions", "warmup", "timeout_s", "curve",
               "quiet"}
# The lab's own programs that timing.engines and timing.stretch may name beside psim's engines,
# each the file of that name in the build folder (psweep's): plain_allpairs is the model written the plain way
# (tests/reference/plain_allpairs.c, -O2, one thread), what a correct straightforward submission
# is, so that such a submission earns its speed points against it; psim's brute is tuned, some 30
# times faster (docs/programs.md, "Weighting judging against speed"). Timed confined and judged
# like a submission, its rows are the lab's (kind `lab` on the board).
LAB_PROGRAMS = ("plain_allpairs",)
# Every speed point is a time over the reference's, so a reference timed slow moves every grade
# of its window, where a slow submission moves its own; and this machine's host slows a run by up
# to half for a second or two now and then, unseen from inside (docs/programs.md, "The
# reference"), so that all five runs of a program can be slow. Each lab program the timing names
# is timed twice as often: as NAME and again as NAME + LAB_AGAIN, whose runs count as NAME's
# (as_lab_runs).
LAB_AGAIN = ".again"
# The timing scene's keys that are not the scene's: the grade sets them per run.
NOT_SCENE_KEYS = ("engine", "T")


@dataclass
class JudgingScene:
    file: str     # as psweep's scene_file: relative to the repository root
    tests: str    # what it tests, for the reports
    # The family (draw.py) a scene is drawn from for each grading, `file` being its public
    # example; None: `file` is judged as it is.
    family: str | None = None
    drawn: Path | None = None  # the scene drawn for this grading, OUT/drawn/NAME.in

    @property
    def name(self) -> str:
        return Path(self.file).stem

    @property
    def run_file(self) -> str:
        """psweep's scene_file: the drawn scene where there is one."""
        return str(self.drawn) if self.drawn else self.file

    @property
    def shown(self) -> str:
        """The scene as runs, the board and the reports name it: drawn/NAME.in, relative to
        the grading's folder, or the file judged as it is."""
        return f"{self.drawn.parent.name}/{self.drawn.name}" if self.drawn else self.file


@dataclass
class GradeConfig:
    path: Path
    scenes: list[JudgingScene]
    judging: dict
    timing: dict
    pin: str
    points: dict  # results.json's points: {"judging": ..., "speed": ...}
    # The readings every output must follow, by key (READINGS); a key left out: either.
    readings: dict = field(default_factory=dict)
    submission: dict = field(default_factory=dict)  # SUBMISSION_KEYS
    curve: SpeedCurve = SpeedCurve()  # timing.curve: a speed test's points from its times
    quiet: Quiet = Quiet()            # timing.quiet: the wait for quiet and what busy runs count

    @property
    def slow_factor(self) -> int:
        return self.submission.get("slow_factor", 1)

    @property
    def repetitions(self) -> int:
        """The timed runs of each program and T (timing.repetitions)."""
        return self.timing.get("repetitions", 3)

    @property
    def judged_threads(self) -> list:
        """The T of the judging sweep (judging.T)."""
        return self.judging.get("T", [1])

    @property
    def timed_threads(self) -> list:
        """The T of the timing sweep (timing.T)."""
        return self.timing.get("T", [1])

    @property
    def warmup(self) -> int:
        """The untimed runs before them (timing.warmup)."""
        return self.timing.get("warmup", 1)

    @property
    def timeout_s(self) -> float:
        """The most one timed run may take (timing.timeout_s)."""
        return self.timing.get("timeout_s", 600)


@dataclass
class Submission:
    """An entry of the submissions folder. `program` is psweep's name for it (the file name where
    that is a plain one); `path` is what runs, None when the entry is not graded (`note` says
    why); `note` also says what a graded entry is when that is not plain (a symlink)."""
    name: str
    program: str
    path: Path | None
    note: str = ""
    source: Path | None = None  # a folder of sources, built (build.py) into `path`
    build_log: str = ""

    @property
    def shown(self) -> str:
        return shown(self.name)


def shown(name: str) -> str:
    """A file name as every report shows it: control characters escaped (a newline as \\n), the
    rest as it is, non-ASCII letters included."""
    return "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in name)


# Larger files are refused before the sandbox copies them in (a 2 GB sparse file, 4 KB on disk,
# was copied in full for every psweep): by apparent size and by blocks.
MAX_SUBMISSION_BYTES = 64 << 20

PLAIN = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def _program_names(names: list[str]) -> list[str]:
    """psweep's program name of each file name: the name itself where it is a plain one and not
    a lab program's (LAB_PROGRAMS: a student may well call a file plain_allpairs), else its
    letters and digits with '_' for the rest, made unique with -2, -3, ..."""
    lab = set(LAB_PROGRAMS) | {name + LAB_AGAIN for name in LAB_PROGRAMS}
    own = {n for n in names if PLAIN.fullmatch(n) and n not in lab}
    taken = own | lab
    out = []
    for name in names:
        if name in own:
            out.append(name)
            continue
        base = re.sub(r"[^A-Za-z0-9_.-]", "_", name.encode("ascii", "replace").decode())
        base = "_" + base.lstrip(".-") if not PLAIN.fullmatch(base) else base
        candidate, k = base, 2
        while candidate in taken:
            candidate, k = f"{base}-{k}", k + 1
        taken.add(candidate)
        out.append(candidate)
    return out


def _entry(folder: Path, path: Path) -> tuple[Path | None, str]:
    """What runs for one entry and what to say of it."""
    if path.is_symlink():
        target = Path(os.readlink(path))
        real = path.resolve()
        if not real.exists():
            return None, f"a symlink to {shown(str(target))}, which does not exist: not graded"
        if real.parent != folder.resolve():
            return None, (f"a symlink to {shown(str(real))}, outside the submissions folder: "
                          "not graded")
        if not real.is_file():
            return None, f"a symlink to {shown(real.name)}, not a file: not graded"
        return real, f"a symlink to {shown(real.name)}"
    if path.is_dir():
        return None, FOLDER_NOTE
    if not path.is_file():
        return None, "not a regular file: not graded"
    st = path.stat()
    if max(st.st_size, st.st_blocks * 512) > MAX_SUBMISSION_BYTES:
        return None, (f"{st.st_size} bytes, more than a submission may be "
                      f"({MAX_SUBMISSION_BYTES >> 20} MiB): not graded")
    return path, ""


FOLDER_NOTE = ("a folder without a Makefile: not graded (a submission is an executable file, or "
               "a folder of sources with a Makefile or built by the grade config's "
               "submission.build)")


def find_submissions(folder: str | Path) -> list[Submission]:
    """Every entry of `folder` whose name does not start with '.', sorted by name; each is
    graded or says why not."""
    folder = Path(folder)
    if not folder.exists():
        raise InputError(f"submissions folder {folder} does not exist")
    if not folder.is_dir():
        raise InputError(f"{folder} is not a folder (expected a folder of submissions, "
                         "one executable each)")
    entries = sorted(p for p in folder.iterdir() if not p.name.startswith("."))
    if not entries:
        raise InputError(f"{folder} holds no submission (each entry whose name does not "
                         "start with '.' is one)")
    names = _program_names([p.name for p in entries])
    return [Submission(p.name, program, *_entry(folder, p),
                       source=p if p.is_dir() and not p.is_symlink() else None)
            for p, program in zip(entries, names)]


def _keys(section: dict, allowed: set[str], where: str) -> None:
    unknown = sorted(set(section) - allowed)
    if unknown:
        raise InputError(f"{where}.{unknown[0]}: unknown key (expected one of "
                         f"{', '.join(sorted(allowed))})")


def _names(timing: dict, key: str, path: Path) -> list[str]:
    """timing.engines or timing.stretch: a list of psim's engines and the lab's programs
    (LAB_PROGRAMS; psweep checks the engines' names)."""
    names = timing.get(key, [])
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise InputError(f'{path}: timing.{key}: expected a list of psim\'s engines and the '
                         f'lab\'s programs ({", ".join(LAB_PROGRAMS)}), e.g. ["plain_allpairs"]')
    return names


def _section(raw: dict, key: str, allowed: set[str], path: Path) -> dict:
    section = raw.get(key)
    if not isinstance(section, dict):
        raise InputError(f"{path}: {key}: expected an object")
    _keys(section, allowed, f"{path}: {key}")
    return section


def _family(entry: dict, where: str) -> str | None:
    """A judging scene's family: one of draw.py's (families.py), or none."""
    family = entry.get("family")
    if family is not None and family not in FAMILIES:
        raise InputError(f"{where}.family: unknown family {json.dumps(family)} (expected one "
                         f"of {', '.join(FAMILIES)}; or no key: the file judged as it is)")
    return family


def _judging_seed(judging: dict, path: Path) -> None:
    seed = judging.get("seed")
    if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)
                             or not 0 <= seed < 1 << 64):
        raise InputError(f"{path}: judging.seed: expected an integer from 0 to 2^64 - 1 (it pins "
                         "the drawn judging scenes; leave it out to draw them afresh for each "
                         f"grading), got {json.dumps(seed)}")


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
            raise InputError(f'{where}: expected {{"file": "scenes/x.in", "family": "...", '
                             '"tests": "..."}')
        _keys(entry, {"file", "tests", "family"}, where)
        scene = JudgingScene(entry["file"], str(entry.get("tests", "")),
                             _family(entry, where))
        if not Path(scene.file).is_file():
            raise InputError(f"{where}.file: {scene.file} not found (paths are relative to the "
                             "repository root)")
        if any(s.name == scene.name for s in scenes):
            raise InputError(f"{where}.file: a second scene named {scene.name} (each scene's "
                             "results go to judge/<file name without .in>)")
        if is_board_column(scene.name):
            raise InputError(f"{where}.file: a scene named {scene.name}, a column of the "
                             "scoreboard already (each scene's verdicts are the column of its "
                             "file name without .in): rename the file")
        scenes.append(scene)
    _judging_seed(judging, path)
    if not isinstance(timing.get("scene"), dict):
        raise InputError(f"{path}: timing.scene: expected an object of psweep base keys "
                         '({"N": 1000, "L": 20000, "r": 1, "S": 1000}; a "seed" pins the scene, '
                         "else each grading draws one)")
    for key in NOT_SCENE_KEYS:
        if key in timing["scene"]:
            raise InputError(f"{path}: timing.scene.{key}: not a key of the scene (the engines "
                             "are timing.engines and timing.stretch, the thread counts timing.T)")
    engines = _names(timing, "engines", path)
    for i, name in enumerate(_names(timing, "stretch", path)):
        if name in engines:
            raise InputError(f"{path}: timing.stretch[{i}]: {name} is in timing.engines too (an "
                             "reference earns speed points or is the stretch, not both)")
    points = raw.get("points", DEFAULT_POINTS)
    if (not isinstance(points, dict) or set(points) != set(DEFAULT_POINTS)
            or not all(isinstance(v, (int, float)) and v >= 0 for v in points.values())):
        raise InputError(f'{path}: points: expected {{"judging": P, "speed": Q}}, each a '
                         "number of points >= 0")
    submission = _submission(raw, path)
    readings = {key: raw[key] for key in READINGS if key in raw}
    for key, value in readings.items():
        if value not in READINGS[key]:
            raise InputError(f"{path}: {key}: expected one of {', '.join(READINGS[key])} (or no "
                             f"key: either reading), got {json.dumps(value)}")
    return GradeConfig(path=path, scenes=scenes, judging=judging, timing=timing,
                       pin=raw.get("pin", "close"), points=points, readings=readings,
                       submission=submission,
                       curve=read_curve(timing, f"{path}: timing"),
                       quiet=read_quiet(timing, f"{path}: timing"))


def _submission(raw: dict, path: Path) -> dict:
    """The `submission` key, its shape checked; psweep checks the placeholders and names."""
    if "submission" not in raw:
        return {}
    submission = _section(raw, "submission", SUBMISSION_KEYS, path)
    args = submission.get("args", [])
    if not isinstance(args, list) or not all(isinstance(a, str) for a in args):
        raise InputError(f'{path}: submission.args: expected a list of strings, e.g. ["{{T}}"] '
                         "(the thread count as the first argument)")
    env = submission.get("env", {})
    if not isinstance(env, dict) or not all(isinstance(v, str) for v in env.values()):
        raise InputError(f'{path}: submission.env: expected an object of strings, e.g. '
                         '{"SIM_VERBOSE": "0"}')
    for key in ("build", "program"):
        if key in submission and (not isinstance(submission[key], str)
                                  or not submission[key].strip()):
            raise InputError(f"{path}: submission.{key}: expected a non-empty string, e.g. "
                             + ('"make" or "gcc -O2 -fopenmp -o sim *.c -lm"' if key == "build"
                                else '"sim" (the executable the build makes)'))
    if ".." in Path(submission.get("program", "")).parts:
        raise InputError(f"{path}: submission.program: a path inside the submission's folder, "
                         f"without '..', got {json.dumps(submission['program'])}")
    timeout = submission.get("build_timeout_s", 1)
    if not isinstance(timeout, (int, float)) or isinstance(timeout, bool) or timeout <= 0:
        raise InputError(f"{path}: submission.build_timeout_s: expected a number of seconds > 0, "
                         f"got {json.dumps(timeout)}")
    k = submission.get("slow_factor", 1)
    if not isinstance(k, int) or isinstance(k, bool) or k < 1:
        raise InputError(f"{path}: submission.slow_factor: expected the sub-steps K every "
                         f"submission is built for, an integer >= 1, got {json.dumps(k)}")
    numbers = submission.get("numbers", "time units")
    if numbers not in ("time units", "sub-steps") or (numbers == "sub-steps" and k == 1):
        raise InputError(f"{path}: submission.numbers: expected \"time units\" (the 2019 format) "
                         f"or, with a slow_factor above 1, \"sub-steps\" (every sub-step printed, "
                         f"numbered to S x K, velocities per sub-step), got {json.dumps(numbers)}")
    return submission


def programs(submissions: dict[str, Path], submission: dict) -> dict:
    """psweep's `programs` key: each submission (program name -> path) as the convention above
    runs it, with the grade config's `submission` arguments, environment and K."""
    extra = {key: submission[key] for key in ("env", "slow_factor", "numbers") if key in submission}
    return {name: {"command": [literal(str(path.absolute())), *submission.get("args", [])],
                   "input": "stdin", "uses": ["T"], **extra}
            for name, path in submissions.items()}


def as_lab_runs(runs):
    """A grading's runs (a DataFrame) with each lab program's runs again (LAB_AGAIN) named as
    the program's."""
    return runs.assign(engine=runs["engine"].replace(
        {name + LAB_AGAIN: name for name in LAB_PROGRAMS}))


def lab_commands(lab: dict[str, Path]) -> dict:
    """psweep's `programs` key for the lab's programs: each takes K as its argument (a grading
    at a submission's K runs them at that K)."""
    return {name: {"command": [literal(str(path.absolute())), "{K}"], "input": "stdin",
                   "uses": ["T", "slow_factor"]} for name, path in lab.items()}


def scene_keys(config: GradeConfig) -> dict:
    """psweep base keys every sweep of a grading shares: the submissions' K."""
    return {"slow_factor": config.slow_factor} if config.slow_factor != 1 else {}


def literal(text: str) -> str:
    """`text` as psweep's command placeholders read it: braces doubled, so that a file named
    bob{x} is that file, not an unknown placeholder that stops the whole grading."""
    return text.replace("{", "{{").replace("}", "}}")


def required_reading(config: GradeConfig) -> dict:
    """psweep's `reading` and `overlap_reading` keys where the grade config requires them."""
    return dict(config.readings)


def judging_config(config: GradeConfig, scene: JudgingScene, submissions: dict[str, Path]) -> dict:
    """One judging scene: every submission once per T (psim check judges each T's output)."""
    names = list(submissions)
    return {
        **required_reading(config),
        "name": f"judge-{scene.name}",
        "description": f"make grade: {scene.tests}",
        "scene_file": scene.run_file,
        "base": {"engine": names[0], "T": 1, **scene_keys(config)},
        "sweep": {"engine": names, "T": config.judged_threads},
        "programs": programs(submissions, config.submission),
        "repetitions": 1, "warmup": 0, "pin": config.pin,
        "timeout_s": config.judging.get("timeout_s", 30),
    }


def timing_seed(config: GradeConfig) -> tuple[int, bool]:
    """The timing scene's seed and whether the config pins it. Unpinned, it is drawn afresh for
    each grading, so that no submission can carry the timing scene's answer: the scene is public
    and psim's answer to a pinned one is a command away."""
    seed = config.timing["scene"].get("seed")
    if seed is not None:
        return seed, True
    return secrets.randbelow(1 << 32), False


def timed_engines(config: GradeConfig) -> list[str]:
    """The lab's references on the timing scene, psim's engines and the lab's programs: those
    the speed points are against, then the stretch."""
    return config.timing.get("engines", []) + config.timing.get("stretch", [])


def lab_programs(config: GradeConfig, build: Path) -> dict[str, Path]:
    """The lab's programs the timing names (name -> its file in `build`, psweep's folder)."""
    lab = {}
    for key in ("engines", "stretch"):
        for i, name in enumerate(config.timing.get(key, [])):
            if name in LAB_PROGRAMS:
                path = build / name
                if not path.is_file():
                    raise InputError(f"{config.path}: timing.{key}[{i}]: {name}, the lab's "
                                     f"program, is not built ({path} is missing: make tools)")
                lab[name] = path
    return lab


def timing_config(config: GradeConfig, submissions: dict[str, Path], seed: int,
                  lab: dict[str, Path]) -> dict:
    """The timing sweep: the lab's references (psim's engines, and `lab`, its programs as
    lab_programs gives them, run as a submission is) and the submissions, then each lab program
    again (LAB_AGAIN)."""
    timing = config.timing
    again = {name + LAB_AGAIN: path for name, path in lab.items()}
    settings = {
        **required_reading(config),
        "name": "timing",
        "description": "make grade: the submissions timed beside psim's engines",
        "base": {"engine": "brute", "T": 1, **timing["scene"], "seed": seed,
                 **scene_keys(config)},
        "sweep": {"engine": timed_engines(config) + list(submissions) + list(again),
                  "T": config.timed_threads},
        "repetitions": config.repetitions, "warmup": config.warmup,
        "pin": config.pin, "timeout_s": config.timeout_s,
        "quiet_wait_s": config.quiet.wait_s,
    }
    if submissions or lab:
        settings["programs"] = {**lab_commands({**lab, **again}),
                                **programs(submissions, config.submission)}
    return settings


def _common_keys(config: GradeConfig, shown: dict[str, str], first: int) -> dict[str, str]:
    """The keys every generated config takes from the grade config or a submission (`shown`:
    psweep's name -> the name shown, of each submission the config runs, in its order), the
    submissions from sweep.engine[first] on."""
    keys = {"pin": f"{config.path}: pin", "reading": f"{config.path}: reading",
            "overlap_reading": f"{config.path}: overlap_reading",
            "base.slow_factor": f"{config.path}: submission.slow_factor"}
    for i, (program, name) in enumerate(shown.items()):
        keys[f"sweep.engine[{first + i}]"] = keys[f"programs.{program}"] = f"the submission {name}"
        for key in ("env", "slow_factor", "numbers"):
            keys[f"programs.{program}.{key}"] = f"{config.path}: submission.{key}"
        for j in range(len(config.submission.get("args", []))):
            keys[f"programs.{program}.command[{j + 1}]"] = f"{config.path}: submission.args[{j}]"
    return keys


def judging_keys(config: GradeConfig, index: int, shown: dict[str, str]) -> dict[str, str]:
    """Where the keys of judging_config(config, config.scenes[index], ...) come from, in the
    words psweep's messages are translated to (translate)."""
    return {**_common_keys(config, shown, 0),
            "scene_file": f"{config.path}: judging.scenes[{index}].file",
            "sweep.T": f"{config.path}: judging.T",
            "timeout_s": f"{config.path}: judging.timeout_s"}


def timing_keys(config: GradeConfig, shown: dict[str, str]) -> dict[str, str]:
    """Where the keys of timing_config's output come from (base.engine and base.T are grade's
    own: the timing scene may not set them)."""
    engines, stretch = config.timing.get("engines", []), config.timing.get("stretch", [])
    keys = {**_common_keys(config, shown, len(engines) + len(stretch)),
            "base": f"{config.path}: timing.scene",
            "sweep.engine": f"{config.path}: timing.engines",
            "sweep.T": f"{config.path}: timing.T"}
    keys.update({f"sweep.engine[{i}]": f"{config.path}: timing.engines[{i}]"
                 for i in range(len(engines))})
    keys.update({f"sweep.engine[{len(engines) + i}]": f"{config.path}: timing.stretch[{i}]"
                 for i in range(len(stretch))})
    keys.update({key: f"{config.path}: timing.{key}"
                 for key in ("repetitions", "warmup", "timeout_s")})
    keys["quiet_wait_s"] = f"{config.path}: timing.quiet.wait_s"
    for i, name in enumerate(engines + stretch):
        if name in LAB_PROGRAMS:
            keys[f"programs.{name}"] = keys[f"sweep.engine[{i}]"]
    return keys


# The last component of a key path: `.name` or `[index]`.
LAST_COMPONENT = re.compile(r"(\.[^.\[]*|\[\d+\])$")


def translate(keys: dict[str, str], path: str) -> str | None:
    """A generated config's key path (`base.N`, `sweep.T[1]`) in the grade config's words: the
    longest key of `keys` it starts with, as `keys` names it, and the rest of the path; None
    for a key grade writes itself."""
    head, cut = path, 1
    while cut:
        if head in keys:
            return keys[head] + path[len(head):]
        head, cut = LAST_COMPONENT.subn("", head)
    return None


def refusal(stderr: str, config_path: Path, keys: dict[str, str]) -> str:
    """psweep's refusal of a generated config (`psweep: FILE: KEY: why`) in the grade config's
    words."""
    prefix = f"psweep: {config_path}: "
    for line in stderr.splitlines():
        if line.startswith(prefix):
            path, _, why = line[len(prefix):].partition(": ")
            where = translate(keys, path)
            if where:
                return f"{where}: {why}"
            return f"{config_path}: {path}: {why} (a key grade writes itself)"
    return f"psweep refused {config_path}: {stderr.strip()}"


# The units of psweep's rough durations ("0.4 s", "40 s", "12 min", "5.1 h", "3.2 days").
DURATION_UNITS = {"s": 1, "min": 60, "h": 3600, "days": 86400}


def estimate_s(count: str) -> float:
    """The total estimate of `psweep --dry-run --count`'s table, in seconds; 0 without one."""
    for line in count.splitlines():
        fields = line.split()
        if fields[:1] == ["total"] and len(fields) >= 5 and fields[-1] in DURATION_UNITS:
            return float(fields[-2]) * DURATION_UNITS[fields[-1]]
    return 0.0


def duration(seconds: float) -> str:
    """A grading's time as a person reads it: "40 s", "12 min", "1.5 h"."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


class SweepError(Exception):
    """psweep did not complete a sweep; `status` is the exit status grade passes on."""

    def __init__(self, message: str, status: int):
        super().__init__(message)
        self.status = status


class SweepRunner:
    """Runs psweep on one generated config at a time (kept beside the results: the command to
    rerun one sweep); its progress and verdicts go to the terminal as they come. When psweep
    dies, says which run was under way (psweep's OUT/tmp/running)."""

    def __init__(self, psweep: str, unconfined: bool = False):
        self.psweep = psweep
        self.unconfined = unconfined

    def _run(self, settings: dict, config_path: Path, arguments: list[str],
             capture: bool = False) -> subprocess.CompletedProcess:
        config_path.parent.mkdir(parents=True, exist_ok=True)
        config_path.write_text(json.dumps(settings, indent=2) + "\n")
        try:
            return subprocess.run([self.psweep, str(config_path), *arguments],
                                  capture_output=capture, text=True)
        except OSError as err:
            raise SweepError(f"cannot run psweep {self.psweep}: {err.strerror} (make build "
                             "first, or --psweep PATH)", 2) from None

    def check(self, settings: dict, config_path: Path, keys: dict[str, str]) -> float:
        """psweep's dry run of one generated config, before any sweep runs: what it refuses
        (exit 2) is said in the grade config's words, `keys` as judging_keys gives them.
        Returns psweep's estimate of the sweep, in seconds."""
        done = self._run(settings, config_path, ["--dry-run", "--count"], capture=True)
        if done.returncode == 2:
            raise InputError(refusal(done.stderr, config_path, keys))
        if done.returncode != 0:
            raise SweepError(f"psweep --dry-run stopped with exit status {done.returncode} on "
                             f"{config_path}: {done.stderr.strip()}", 1)
        return estimate_s(done.stdout)

    def __call__(self, settings: dict, config_path: Path, out: Path, resume: bool = False
                 ) -> None:
        """`resume`: only the runs OUT/runs.csv lacks (psweep --resume), each once."""
        done = self._run(settings, config_path, ["--out", str(out), "--yes"]
                         + (["--resume"] if resume else [])
                         + (["--unconfined"] if self.unconfined else []))
        if done.returncode == 2:
            raise SweepError(f"psweep refused {config_path} (its message above; the program "
                             "names are the submissions' file names)", 2)
        if done.returncode != 0:
            running = out / "tmp" / "running"
            during = ""
            if running.is_file():
                engine, run_id, rep = (running.read_text().split("\t") + ["", "", ""])[:3]
                during = f", while {engine} ran ({run_id}, repetition {rep.strip()})"
            raise SweepError(f"psweep stopped with exit status {done.returncode} on "
                             f"{config_path}{during}",
                             1 if done.returncode < 128 else done.returncode)
