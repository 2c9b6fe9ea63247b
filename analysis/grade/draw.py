"""The judging scenes of one grading, drawn afresh (docs/programs.md, "Drawn judging scenes"): a
judging scene with a `family` in the grade config is not judged as its public file is, which is
in the repository and the Gradescope zip and whose answers psim gives to anyone, but as a scene
drawn from its family (families.py) for this grading, from a seed drawn per grading like the
timing scene's unless `judging.seed` pins it. Each drawn scene is verified through build/psim
to test its rule (its family's checks), drawn again where it does not (at most MAX_DRAWS times),
and kept as OUT/drawn/NAME.in, where staff rerun it; runs and reports name it drawn/NAME.in.

Each scene draws from its own generator, seeded by the grading's seed and the scene's name, so a
pinned seed gives the same scenes whatever else the config holds, and two scenes of one family
differ.
"""
from __future__ import annotations

import json
import random
import secrets
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path

from analysis.common.load import InputError
from analysis.grade.families import FAMILIES, NotExact, Scene
from analysis.grade.plan import GradeConfig, JudgingScene

MAX_DRAWS = 200  # a family's draws fail their checks a few times in ten at most
SEED_LIMIT = 1 << 64
DRAWN = "drawn"  # OUT's folder of the drawn scenes, and the name runs and reports give them


class DrawError(Exception):
    """No scene of a family passed its checks, or psim could not run them (exit status 1)."""


def judging_seed(config: GradeConfig) -> tuple[int, bool]:
    """The drawn judging scenes' seed and whether the config pins it (judging.seed). Unpinned,
    it is drawn afresh for each grading: a pinned seed's scenes are psim runs away from their
    answers, as the public scenes are."""
    seed = config.judging.get("seed")
    if seed is not None:
        return seed, True
    return secrets.randbelow(SEED_LIMIT), False


class Psim:
    """build/psim on drawn scenes, for the families' checks: each run one thread, a few
    milliseconds (the checks' scenes are a few particles, or the two random ones)."""

    def __init__(self, path: Path):
        if not path.is_file():
            raise InputError(f"{path} is missing: the judging scenes are drawn and verified with "
                             "psim (make tools)")
        self.path = path
        self._finals: dict[tuple[str, int], list[tuple]] = {}

    def _run(self, arguments: list[str], text: str) -> str:
        done = subprocess.run([str(self.path), "--threads", "1", *arguments], input=text,
                              capture_output=True, text=True)
        if done.returncode != 0:
            raise DrawError(f"psim refused a drawn scene ({done.stderr.strip()}):\n{text}")
        return done.stdout

    def final(self, scene: Scene, steps: int) -> list[tuple]:
        """Each particle's (x, y, vx, vy, pair collisions, wall collisions) after `steps` time
        units: the scene cut there, in perf mode."""
        text = scene.text(steps, "perf")
        if (text, steps) not in self._finals:
            lines = [line.split() for line in self._run([], text).splitlines()]
            self._finals[text, steps] = [tuple(float(v) for v in f[2:6]) + (int(f[6]), int(f[7]))
                                         for f in lines if len(f) == 8]
        return self._finals[text, steps]

    def counters(self, scene: Scene) -> dict:
        """psim's counters (--metrics) over the whole scene."""
        with tempfile.TemporaryDirectory() as tmp:
            metrics = Path(tmp) / "metrics.json"
            self._run(["--metrics", str(metrics)],
                      scene.text(mode="perf"))
            return json.loads(metrics.read_text())["counters"]

    def write_scene(self, header: str, seed: int) -> str:
        """psim's random scene of `header` at `seed`, every particle written."""
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "scene.in"
            self._run(["--write-scene", str(path), "--seed", str(seed)], header)
            return path.read_text()


def draw_scene(family: str, rng: random.Random, sim: Psim) -> Scene:
    """A scene of `family` that passes every check of its draw."""
    why = "every draw's numbers left the box"
    for _ in range(MAX_DRAWS):
        try:
            drawn = FAMILIES[family](rng, sim)
        except NotExact as err:
            why = str(err)
            continue
        if drawn is None or not drawn.scene.inside():
            continue
        failed = next((why for check in drawn.checks if (why := check(sim))), None)
        if failed is None:
            return drawn.scene
        why = failed
    raise DrawError(f"no scene of the family {family} passed its checks in {MAX_DRAWS} draws "
                    f"(the last: {why})")


def drawn_in(scenes: list[JudgingScene], out: Path) -> list[JudgingScene]:
    """The judging scenes as draw_scenes drew them into OUT/drawn/ before: the scenes of a
    class graded in shards, drawn once for the whole class (shards.py)."""
    judged = []
    for scene in scenes:
        path = out / DRAWN / f"{scene.name}.in"
        if scene.family is not None and not path.is_file():
            raise InputError(f"{path} is missing: the class's judging scenes are drawn by "
                             "grade-slurm plan")
        judged.append(replace(scene, drawn=path.absolute()) if scene.family else scene)
    return judged


def draw_scenes(scenes: list[JudgingScene], seed: int, psim: Path, out: Path
                ) -> list[JudgingScene]:
    """The judging scenes of one grading: each with a family drawn, written to OUT/drawn/, the
    others as they are. A scene left there by an earlier grading is removed first."""
    folder = out / DRAWN
    folder.mkdir(parents=True, exist_ok=True)
    for stale in folder.glob("*.in"):
        stale.unlink()
    sim = Psim(psim)
    judged = []
    for scene in scenes:
        if scene.family is None:
            judged.append(scene)
            continue
        drawn = draw_scene(scene.family, random.Random(f"{seed}/{scene.name}"), sim)
        path = folder / f"{scene.name}.in"
        path.write_text(drawn.text())
        judged.append(replace(scene, drawn=path.absolute()))
    return judged
