"""The judging scenes drawn afresh for each grading (analysis/grade/draw.py, families.py;
docs/programs.md, "Drawn judging scenes"): each family's scenes catch the broken build of
plain_allpairs that its public example catches (tests/check's CHECK_BROKEN_* builds, `make
build`), and plain_allpairs is exact on them; a program that stores psim's answers to the public
judging scenes and runs the wall-tolerance build on anything else gets full judging points on
the public scenes and only its bug's points on drawn ones; two gradings draw different scenes
and seeds, a pinned seed reproduces them; the per-grading seeds (the timing scene's and the
judging scenes') are drawn afresh, which a constant planted in either makes fail.
"""
import csv
import hashlib
import json
import random
import shutil
import subprocess

import pytest

from build_path import BUILD
from entry_point import ROOT, run_tool

from analysis.common.load import InputError
from analysis.grade import families
from analysis.grade.draw import DrawError, Psim, draw_scene, draw_scenes, judging_seed
from analysis.grade.families import FAMILIES
from analysis.grade.plan import read_config, timing_seed

# The broken build (build/check_programs/) each family's scenes must catch, as its public
# example does (docs/programs.md's table); None: no broken build breaks that rule (the
# overlap_receding build follows the overlap reading `always`: test_a_receding_overlap_...).
CATCHES = {"corner": "corner_one_flip", "wall_before_end": "wall_tolerance",
           "wall_beats_pair": "pair_before_wall", "wall_beats_pair_high": "index_order",
           "three_in_row_tie": "two_collisions", "overlap_approaching": "overlap",
           "overlap_receding": None, "head_on": None,
           "three_at_once": "two_collisions", "cradle": "two_collisions",
           "faster_than_box": None, "random": "nan", "dense": "float"}
DRAWS = 3  # scenes drawn per family


@pytest.fixture(scope="module")
def sim():
    return Psim(BUILD / "psim")


def verdict(scene, program, tmp_path) -> str:
    path = tmp_path / "scene.in"
    path.write_text(scene.text())
    built = BUILD / program
    assert built.is_file(), f"{built} is missing: build first (make build)"
    with open(path) as stdin:
        output = subprocess.run([str(built)], stdin=stdin, capture_output=True, text=True).stdout
    (tmp_path / "out.txt").write_text(output)
    done = subprocess.run([str(BUILD / "psim"), "check", str(path), str(tmp_path / "out.txt")],
                          capture_output=True, text=True)
    return done.stdout.split(",")[0].removeprefix("verdict: ")


def test_every_family_has_its_test():
    assert set(CATCHES) == set(FAMILIES)


def test_a_receding_overlap_collided_is_the_always_reading_on_every_draw(sim, tmp_path):
    # Both overlap readings are the handout's (docs/model.md, "Readings"): the family's scenes
    # tell them apart, and the report names the one a program follows.
    rng = random.Random("test/overlap_receding")
    for _ in range(DRAWS):
        path = tmp_path / "scene.in"
        path.write_text(draw_scene("overlap_receding", rng, sim).text())
        for program, reading in (("plain_allpairs", "approaching"),
                                 ("check_programs/overlap_receding", "always")):
            with open(path) as stdin:
                output = subprocess.run([str(BUILD / program)], stdin=stdin, capture_output=True,
                                        text=True).stdout
            (tmp_path / "out.txt").write_text(output)
            done = subprocess.run([str(BUILD / "psim"), "check", str(path),
                                   str(tmp_path / "out.txt")], capture_output=True, text=True)
            assert done.stdout.startswith("verdict: exact, ") and \
                f"overlap {reading}: " in done.stdout.splitlines()[0], (program, done.stdout)


@pytest.mark.parametrize("family", sorted(CATCHES))
def test_each_familys_scenes_test_its_rule(family, sim, tmp_path):
    rng = random.Random(f"test/{family}")
    public = {s.family: s.file for s in read_config(ROOT / "configs" / "grade.json").scenes}
    texts = set()
    for _ in range(DRAWS):
        scene = draw_scene(family, rng, sim)
        texts.add(scene.text())
        assert verdict(scene, "plain_allpairs", tmp_path) == "exact", scene.text()
        if CATCHES[family]:
            broken = verdict(scene, f"check_programs/{CATCHES[family]}", tmp_path)
            assert broken == "violations", (CATCHES[family], scene.text())
    assert len(texts) == DRAWS and (ROOT / public[family]).read_text() not in texts


@pytest.mark.parametrize("family", sorted(set(FAMILIES) - {"random", "dense"}))
def test_every_draw_of_a_hand_made_family_fits_or_is_refused(family):
    """Many draws, without psim: each returns a scene, None (redrawn) or NotExact, never an
    error (a range left empty by a small box once stopped a grading)."""
    rng = random.Random(f"fits/{family}")
    for _ in range(3000):
        try:
            FAMILIES[family](rng, None)
        except families.NotExact:
            pass


def test_a_check_that_never_holds_stops_the_draw(sim, monkeypatch):
    def never(rng, _sim):
        scene = families.Scene(10.0, 1.0, 1, ((5.0, 5.0, 1.0, 0.0),))
        return families.Drawn(scene, [families.counts(scene, 1, {0: (0, 1)}, "a hit")])
    monkeypatch.setitem(FAMILIES, "corner", never)
    with pytest.raises(DrawError, match=r"no scene of the family corner passed its checks in "
                                        r"\d+ draws \(the last: a hit: after time unit 1"):
        draw_scene("corner", random.Random(1), sim)


def test_the_seeds_are_drawn_per_grading_unless_pinned(tmp_path):
    # A constant planted in timing_seed or judging_seed (the timing scene's or the judging
    # scenes' seed, unpinned) fails here: the rest of the suite pins both or reads neither.
    config = read_config(ROOT / "configs" / "grade.json")
    for draw in (timing_seed, judging_seed):
        seeds = {draw(config) for _ in range(4)}
        assert len(seeds) == 4 and all(not pinned for _, pinned in seeds), draw.__name__
    raw = json.loads((ROOT / "configs" / "grade.json").read_text())
    raw["judging"]["seed"] = 12
    raw["timing"]["scene"]["seed"] = 34
    path = tmp_path / "pinned.json"
    path.write_text(json.dumps(raw))
    pinned = read_config(path)
    assert judging_seed(pinned) == (12, True) and timing_seed(pinned) == (34, True)


@pytest.mark.parametrize("change, message", [
    (lambda c: c["judging"]["scenes"][1].update(family="corners"),
     'judging.scenes[1].family: unknown family "corners" (expected one of corner, '),
    (lambda c: c["judging"].update(seed=-1), "judging.seed: expected an integer from 0 to "
                                             "2^64 - 1"),
    (lambda c: c["judging"].update(seed=1 << 64), "judging.seed: expected an integer"),
    (lambda c: c["judging"].update(seed="7"), 'judging.seed: expected an integer from 0 to '
                                              '2^64 - 1 (it pins the drawn judging scenes; '
                                              'leave it out to draw them afresh for each '
                                              'grading), got "7"'),
    (lambda c: c["judging"].update(seed=True), "judging.seed: expected an integer"),
])
def test_a_bad_family_or_seed_is_refused_by_its_key(tmp_path, change, message):
    raw = json.loads((ROOT / "configs" / "grade.json").read_text())
    change(raw)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(raw))
    with pytest.raises(InputError) as err:
        read_config(path)
    assert f"{path}: {message}" in str(err.value)


# The stored-answer program: psim's output for each public judging scene, looked up by the hash
# of the scene psweep gives it; anything else goes to the wall-tolerance build. Run unconfined:
# it reads its answers and the build from the grader's files (what it stores is the point here,
# not how it would carry it through the sandbox: the program ran confined).
STORED = """#!/bin/sh
scene=$(mktemp)
cat > "$scene"
answer="{answers}/$(sha256sum < "$scene" | cut -c1-64)"
if [ -f "$answer" ]; then cat "$answer"; else {wall} < "$scene"; fi
rm -f "$scene"
"""
SCENES = ("scenes/corner.in", "scenes/wall_before_end.in", "scenes/wall_beats_pair.in",
          "scenes/head_on.in")


def stored_answers(folder):
    """psim's output for each public judging scene of configs/grade.json, under the hash of the
    scene as psweep gives it to a program (psim --write-scene's text)."""
    folder.mkdir()
    for scene in read_config(ROOT / "configs" / "grade.json").scenes:
        given = folder / "given.in"
        subprocess.run([str(BUILD / "psim"), "--write-scene", str(given), str(ROOT / scene.file)],
                       check=True)
        output = subprocess.run([str(BUILD / "psim"), str(given)], check=True,
                                capture_output=True, text=True).stdout
        (folder / hashlib.sha256(given.read_bytes()).hexdigest()).write_text(output)
        given.unlink()


def grade_with(root, name, folder, drawn: bool):
    """A grading of `folder` on SCENES (drawn from their families, or the public files as they
    are) at T = 1, and a tiny timing scene drawn per grading; its grades.csv rows and OUT."""
    config = json.loads((ROOT / "configs" / "grade.json").read_text())
    config["judging"]["scenes"] = [dict(s) for s in config["judging"]["scenes"]
                                   if s["file"] in SCENES]
    if not drawn:
        for scene in config["judging"]["scenes"]:
            del scene["family"]
    config["judging"]["T"] = [1]
    config["timing"].update(scene={"N": 20, "L": 1000, "r": 1, "S": 10}, T=[1],
                            repetitions=1, warmup=0)
    path = root / f"{name}.json"
    path.write_text(json.dumps(config))
    out = root / name
    done = run_tool("grade", folder, "--out", out, "--config", path, "--psweep",
                    BUILD / "psweep", "--unconfined", timeout=300)
    assert done.returncode == 0, done.stderr
    with open(out / "grades.csv", newline="") as f:
        grades = {row["name"]: row for row in csv.DictReader(f)}
    return grades, out, done


@pytest.fixture(scope="module")
def gradings(tmp_path_factory):
    root = tmp_path_factory.mktemp("stored")
    stored_answers(root / "answers")
    wall = BUILD / "check_programs" / "wall_tolerance"
    assert wall.is_file(), f"{wall} is missing: build first (make build)"
    folder = root / "submissions"
    folder.mkdir()
    (folder / "stored").write_text(STORED.format(answers=root / "answers", wall=wall))
    (folder / "stored").chmod(0o755)
    shutil.copy(wall, folder / "wall_tolerance")
    return {name: grade_with(root, name, folder, drawn)
            for name, drawn in (("public", False), ("drawn", True), ("again", True))}


def test_stored_answers_earn_full_judging_points_on_the_public_scenes(gradings):
    grades, _, done = gradings["public"]
    assert float(grades["stored"]["judging_score"]) == pytest.approx(70)
    assert float(grades["wall_tolerance"]["judging_score"]) < 70
    assert "has no family: judged as it is, and a submission can carry its answer" in done.stderr


def test_stored_answers_earn_only_their_real_bugs_points_on_drawn_scenes(gradings):
    grades, out, _ = gradings["drawn"]
    stored, wall = grades["stored"], grades["wall_tolerance"]
    assert float(stored["judging_score"]) == pytest.approx(float(wall["judging_score"]))
    assert float(stored["judging_score"]) == pytest.approx(70 * 3 / 4)
    with open(out / "scoreboard.csv", newline="") as f:
        board = {row["name"]: row for row in csv.DictReader(f)}
    assert board["stored"]["wall_before_end"] == "violations"
    assert board["stored"]["scene"] == "drawn/wall_before_end.in K=1"


def test_two_gradings_draw_different_scenes_and_say_their_seeds(gradings):
    (_, out, done), (_, again, _) = gradings["drawn"], gradings["again"]
    meta, meta_again = (json.loads((o / "meta.json").read_text()) for o in (out, again))
    assert meta["judging_seed_source"] == meta_again["judging_seed_source"] == "drawn"
    assert meta["timing_seed_source"] == "drawn"
    assert meta["judging_seed"] != meta_again["judging_seed"]
    assert meta["timing_seed"] != meta_again["timing_seed"]
    names = [s.rsplit("/", 1)[1][:-3] for s in SCENES]
    assert meta["judging_scenes"] == {n: f"drawn/{n}.in" for n in names}
    for n in names:
        assert (out / "drawn" / f"{n}.in").read_text() != (again / "drawn" / f"{n}.in").read_text()
        assert (out / "drawn" / f"{n}.in").read_text() != (ROOT / "scenes" / f"{n}.in").read_text()
    assert (f"grade: judging scenes drawn with seed {meta['judging_seed']}, drawn for this "
            "grading") in done.stderr
    said = f"judging scenes drawn with seed {meta['judging_seed']} (drawn for this grading)"
    for page in [out / "scoreboard.md", *(out / "reports").glob("*.md")]:
        assert said in page.read_text().lower(), page
    report = (out / "reports" / "stored.md").read_text()
    assert "| drawn/corner.in |" in report and str(out) not in report


def test_a_pinned_seed_draws_the_same_scenes(gradings, tmp_path):
    _, out, _ = gradings["drawn"]
    seed = json.loads((out / "meta.json").read_text())["judging_seed"]
    config = read_config(out.parent / "drawn.json")
    redrawn = draw_scenes(config.scenes, seed, BUILD / "psim", tmp_path)
    for scene in redrawn:
        assert scene.drawn.read_text() == (out / "drawn" / f"{scene.name}.in").read_text()
