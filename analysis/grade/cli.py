"""A grading run for many submissions (`make grade PROGRAMS=DIR`): every submission of DIR judged
by psim check on the judging scenes of the grade config and timed beside the lab's references
(its plain program, psim's engines) on its timing scene, all through psweep (plan.py); then
OUT/scoreboard.csv (board.py, printed) and OUT/reports/NAME.md (report.py).

Usage: /usr/bin/python3 -m analysis grade DIR [--out OUT] [--config configs/grade.json] [--psweep PATH]
Exit status: 0 when the grading ran, whatever the submissions did (a crash, a hang, garbage: each
is a verdict); 2 bad input, before the first run (DIR missing, not a folder or empty; a bad grade
config, named by its own key, whatever psweep's dry run of the generated configs refuses
included; a submission named like an engine); 1 psweep stopped otherwise (an I/O error), or
no judging scene of a family passed its checks (draw.py);
psweep's 130/143 when it was interrupted.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, replace
from datetime import datetime, timezone
from pathlib import Path

import pandas as pd

from analysis.common.csv_out import write_csv
from analysis.common.load import InputError, load_results
from analysis.common.markdown import cell, markdown_table
from analysis.common.page import write_pages
from analysis.grade.board import (TIMING, SceneColumn, grade_board, scene_verdicts,
                                  scoreboard_page, with_scenes)
from analysis.grade.build import build, buildable
from analysis.grade.classreport import class_page
from analysis.grade.estimate import timing_estimates_s
from analysis.grade.draw import DRAWN, DrawError, draw_scenes, judging_seed
from analysis.grade.gradescope import beside, write_grades
from analysis.grade.plan import (MAX_SUBMISSION_BYTES, GradeConfig, Submission, SweepError,
                                 SweepRunner, as_lab_runs, duration,
                                 find_submissions, judging_config, judging_keys, lab_programs,
                                 read_config, timed_engines, timing_config, timing_keys,
                                 timing_seed)
from analysis.grade.report import Grading, submission_report


def build_sources(entries: list[Submission], config: GradeConfig, psweep: str, out: Path,
                  unconfined: bool) -> None:
    """Every entry that is a folder of sources built confined into OUT/builds/<program>/
    (build.py): its path the program it made, or its note why it is not graded."""
    for e in entries:
        if e.source is None or not buildable(e.source, config.submission):
            continue
        print(f"grade: building {e.shown} (`{config.submission.get('build', 'make')}`)",
              file=sys.stderr)
        built = build(e.source, config.submission, psweep, out / "builds" / e.program,
                      MAX_SUBMISSION_BYTES, unconfined)
        e.path, e.note, e.build_log = built.program, built.note, built.log
        if e.path is not None:
            e.note = f"built from its sources by `{config.submission.get('build', 'make')}`"


def not_graded(entries: list[Submission]) -> pd.DataFrame:
    """A row per entry that was not run, below every graded one."""
    return pd.DataFrame([{"name": e.program, "kind": "program", "verdict": "failed",
                          "scene": "", "first_violation": e.note} for e in entries])


def write_meta(out: Path, config, seed: int, pinned: bool, entries: list[Submission],
               judging: tuple[int, bool]) -> None:
    """OUT/meta.json: what this grading was, beside each sweep's own meta.json."""
    out.mkdir(parents=True, exist_ok=True)
    meta = {"config": str(config.path), "timing_seed": seed,
            "timing_seed_source": "pinned" if pinned else "drawn",
            "judging_seed": judging[0], "judging_seed_source": "pinned" if judging[1] else "drawn",
            "judging_scenes": {s.name: s.shown for s in config.scenes},
            "submissions": [e.shown for e in entries],
            "date": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    (out / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")


def drawn_line(config: GradeConfig, drawing: tuple[int, bool]) -> str:
    """What the reports and the scoreboard page say of the judging scenes' draw."""
    fixed = [s.file for s in config.scenes if s.family is None]
    line = (f"judging scenes drawn with seed {drawing[0]} "
            f"({'pinned by the config' if drawing[1] else 'drawn for this grading'}), "
            f"each kept in the grading's {DRAWN}/")
    return line + (f"; judged as they are: {', '.join(fixed)}" if fixed else "")


def say_drawn(config: GradeConfig, drawing: tuple[int, bool]) -> None:
    """The draw's seed on the terminal, and what a pinned seed or a fixed scene gives away."""
    seed, pinned = drawing
    print(f"grade: judging scenes drawn with seed {seed}, " + (
        "pinned by the config: a submission can carry the answers to a pinned seed's scenes "
        "(leave judging.seed out to draw them per grading)" if pinned else
        "drawn for this grading"), file=sys.stderr)
    for i, scene in enumerate(config.scenes):
        if scene.family is None:
            print(f"grade: judging.scenes[{i}] ({scene.file}) has no family: judged as it is, "
                  "and a submission can carry its answer", file=sys.stderr)


def check_configs(sweep: SweepRunner, config: GradeConfig, submissions: dict[str, Path],
                  shown: dict[str, str], seed: int, lab: dict[str, Path], out: Path) -> float:
    """Every psweep config of the grading through psweep's dry run before the first run: a bad
    key of the grade config is refused now, in its own name, not once every judging run has
    run. The timing config as if every submission were timed: those that will be are some of
    them. Returns the sum of psweep's estimates: the grading's, every sweep's runs, judging runs
    and checks (the cost model's, with a program costed as a plain all-pairs one)."""
    names = {program: shown[program] for program in submissions}
    total = 0.0
    if submissions:
        for i, scene in enumerate(config.scenes):
            total += sweep.check(judging_config(config, scene, submissions),
                                 out / "configs" / f"judge-{scene.name}.json",
                                 judging_keys(config, i, names))
    return total + sweep.check(timing_config(config, submissions, seed, lab),
                               out / "configs" / "timing.json", timing_keys(config, names))


def say_timing_estimate(sweep: SweepRunner, config: GradeConfig, judging: list, timed: dict,
                        shown: dict[str, str], seed: int, lab: dict[str, Path],
                        out: Path) -> float:
    """Before the timing sweep: its estimate, the lab's references by psweep's cost model and
    each submission from its own judging runs (estimate.py), the slowest named. Returns it."""
    references = sweep.check(timing_config(config, {}, seed, lab), out / "configs" / "timing.json",
                             timing_keys(config, {}))
    timing = config.timing
    runs_per_T = config.repetitions + config.warmup + 1  # + its judging run
    own = timing_estimates_s(pd.concat([s.runs for s in judging]) if judging else pd.DataFrame(),
                             list(timed), timing["scene"], config.timed_threads, runs_per_T,
                             config.timeout_s) if timed else {}
    slowest = sorted(own.items(), key=lambda item: -item[1])
    named = ", ".join(f"{shown[name]} {duration(s)}" for name, s in slowest[:5])
    total = references + sum(own.values())
    print(f"grade: the timing, about {duration(total)}: the lab's references {duration(references)} "
          f"(the cost model's estimate)" + (f", the submissions from their own judging runs "
                                            f"{duration(sum(own.values()))} (the slowest: {named}"
                                            f"{', ...' if len(slowest) > 5 else ''})" if own else ""),
          file=sys.stderr)
    return total


def scene_columns(config: GradeConfig, labelled: pd.DataFrame, timing_scene: str
                  ) -> list[SceneColumn]:
    """The board's column of each scene that ran, in the config's order, the timing scene's
    last."""
    labels = dict(zip(labelled["scene_file"], labelled["scene"]))
    return [SceneColumn(labels[s.shown], s.name, s.shown, s.tests) for s in config.scenes
            if s.shown in labels] + [SceneColumn(
                timing_scene, TIMING, f"the timing scene ({timing_scene})", "the timed runs' "
                "final states (perf mode) and a judging run of the same particles (print mode, "
                "step by step)")]


@dataclass
class Setup:
    """What every step of a grading shares: the submissions (all of DIR's entries, or one
    shard's group of them, named as the whole folder names them), the config with its judging
    scenes drawn, the seeds, and psweep. `who` prefixes the progress lines (a shard says which
    part of the class it is)."""
    source: str
    entries: list[Submission]
    config: GradeConfig
    lab: dict[str, Path]
    sweep: SweepRunner
    psweep: str
    timing_seed: tuple[int, bool]  # the seed and whether the config pins it
    drawing: tuple[int, bool]      # the judging scenes' seed, likewise
    unconfined: bool = False
    who: str = ""

    @property
    def submissions(self) -> dict[str, Path]:
        return {e.program: e.path for e in self.entries if e.path is not None}

    @property
    def shown(self) -> dict[str, str]:
        return {e.program: e.shown for e in self.entries}

    def say(self, line: str) -> None:
        print(f"grade: {self.who}{line}", file=sys.stderr)


def setup(submissions_dir: str, config_path: str, psweep: str, unconfined: bool = False,
          seeds: tuple[tuple[int, bool], tuple[int, bool]] | None = None,
          only: set[str] | None = None) -> Setup:
    """The grading of DIR before anything is built, drawn or run. `seeds`: the timing's and the
    judging's (seed, pinned), drawn here unless given (a shard takes the class's); `only`: the
    entries' file names to keep (a shard's group), the others' program names unchanged."""
    entries = find_submissions(submissions_dir)
    if only is not None:
        entries = [e for e in entries if e.name in only]
    config = read_config(config_path)
    timing, drawing = seeds or (timing_seed(config), judging_seed(config))
    return Setup(submissions_dir, entries, config, lab_programs(config, Path(psweep).parent),
                 SweepRunner(psweep, unconfined), psweep, timing, drawing, unconfined)


def judge(s: Setup, out: Path, stages: int, start: float, resume: bool = False) -> list:
    """One psweep per judging scene into OUT/judge/SCENE (`resume`: only the runs its runs.csv
    lacks, as a requeued shard needs); each sweep's results, scenes named as the reports name
    them."""
    judging = []
    for k, scene in enumerate(s.config.scenes if s.submissions else []):
        folder = out / "judge" / scene.name
        s.say(f"[{k + 1}/{stages}] judging on {scene.shown}, "
              f"{duration(time.monotonic() - start)} so far")
        s.sweep(judging_config(s.config, scene, s.submissions),
                out / "configs" / f"judge-{scene.name}.json", folder, resume)
        judged = load_results(folder)
        # Named as the reports name it (drawn/NAME.in), not by the grader's path.
        judged.runs["scene_file"] = scene.shown
        judging.append(judged)
    return judging


def to_time(s: Setup, judging: list) -> dict[str, Path]:
    """The submissions the timing runs: those with a judging run that ended ok. One that never
    ran to its end (crashes at once, hangs, cannot be executed) has nothing to time, and a hang
    would cost every timing run its whole timeout."""
    ran = set(pd.concat([j.ok for j in judging])["engine"]) if judging else set()
    skipped = sorted(set(s.submissions) - ran)
    if skipped:
        s.say(f"not timed, no judging run ended ok: {', '.join(skipped)}")
    return {name: path for name, path in s.submissions.items() if name in ran}


def say_timing_seed(s: Setup) -> None:
    seed, pinned = s.timing_seed
    s.say(f"timing scene seed {seed}, " + (
        "pinned by the config: a submission can carry the answer to a pinned scene (leave "
        "timing.scene.seed out to draw one per grading)" if pinned else "drawn for this grading"))


def grade(submissions_dir: str, out: Path, config_path: str, psweep: str,
          unconfined: bool = False) -> pd.DataFrame:
    s = setup(submissions_dir, config_path, psweep, unconfined)
    build_sources(s.entries, s.config, psweep, out, unconfined)
    for e in s.entries:
        if e.note:
            s.say(f"{e.shown}: {e.note}")
    if s.submissions:
        s.config = replace(s.config, scenes=draw_scenes(s.config.scenes, s.drawing[0],
                                                        Path(psweep).parent / "psim", out))
        say_drawn(s.config, s.drawing)
    estimate = check_configs(s.sweep, s.config, s.submissions, s.shown, s.timing_seed[0],
                             s.lab, out)
    stages = (len(s.config.scenes) if s.submissions else 0) + 1
    s.say(f"{len(s.submissions)} submissions "
          f"({', '.join(e.shown for e in s.entries if e.path)}), "
          f"{len(s.config.scenes)} judging scenes, then the timing: {stages} sweeps, about "
          f"{duration(estimate)} in all (the cost model's estimate)")
    start = time.monotonic()
    judging = judge(s, out, stages, start)
    timed = to_time(s, judging)
    say_timing_seed(s)
    write_meta(out, s.config, *s.timing_seed, s.entries, s.drawing)
    timing_estimate = say_timing_estimate(s.sweep, s.config, judging, timed, s.shown,
                                          s.timing_seed[0], s.lab, out)
    timing_start = time.monotonic()
    s.say(f"[{stages}/{stages}] timing, {duration(time.monotonic() - start)} so far")
    s.sweep(timing_config(s.config, timed, s.timing_seed[0], s.lab),
            out / "configs" / "timing.json", out / "timing")
    s.say(f"the sweeps took {duration(time.monotonic() - start)} (estimated "
          f"{duration(estimate)}), the timing {duration(time.monotonic() - timing_start)} "
          f"(estimated {duration(timing_estimate)} after the judging)")
    programs = judging[0].meta["programs"] if judging else {}
    return score(s, out, judging, [load_results(out / "timing")], programs,
                 f"{len(s.entries)} submissions of {submissions_dir}")


def score(s: Setup, out: Path, judging: list, timings: list, programs: dict,
          title: str) -> pd.DataFrame:
    """Every file of the grading's OUT from its sweeps' results: the judging sweeps' and the
    timing windows' (`timings`: one on one machine; one per shard and window on a cluster, each
    submission timed in one of them beside the references), `programs` meta.json's record of
    each submission. Returns the board."""
    config, shown, submissions, lab = s.config, s.shown, s.submissions, s.lab
    sweeps = judging + timings
    runs = as_lab_runs(pd.concat([r.runs.assign(results=str(r.directory)) for r in sweeps],
                                 ignore_index=True))
    labelled = with_scenes(runs)
    declaration = timings[0].declaration
    # The lab's programs are judged as a submission is (a reference that is not exact would
    # show), and are the lab's rows.
    per_scene = scene_verdicts(labelled, set(submissions) | set(lab), declaration)
    per_scene = own_windows(per_scene, labelled, timings, set(submissions), set(lab),
                            declaration)
    per_scene.loc[per_scene["name"].isin(lab), "kind"] = "lab"
    per_scene = pd.concat([per_scene, not_graded([e for e in s.entries if e.path is None])],
                          ignore_index=True)
    timing_scene = labelled[labelled["results"] == str(timings[0].directory)]["scene"].iloc[0]
    scenes = scene_columns(config, labelled, timing_scene)
    timed = labelled[labelled["results"].isin([str(t.directory) for t in timings])]
    engines = config.timing.get("engines", [])
    results = write_grades(out, shown, per_scene, [x.label for x in scenes[:-1]], timed,
                           engines, config.points, config.timing.get("stretch", []),
                           config.curve, config.quiet)
    # Each T judged alone as well, so that the board's verdict per T hides nothing behind the
    # worst over T.
    by_T = {t: scene_verdicts(labelled[labelled["T"] == t], set(submissions) | set(lab),
                              declaration) for t in sorted(labelled["T"].dropna().unique())}
    places = {name: beside(timed, name, engines, config.quiet) for name in submissions
              if name in set(timed["engine"])}
    places.update({name: {"node": ", ".join(sorted(set(map(str, rows["node"].dropna()))))}
                   for name, rows in timed[timed["engine"].isin(timed_engines(config))]
                   .groupby("engine")} if "node" in timed else {})
    board = grade_board(per_scene, scenes, {p: r["score"] for p, r in results.items()}, by_T,
                        places)

    reports = out / "reports"
    reports.mkdir(parents=True, exist_ok=True)
    # A report left from an earlier grading would stand for a submission no longer graded.
    for stale in [*reports.glob("*.md"), *reports.glob("*.html")]:
        stale.unlink()
    grading = Grading(out=out, runs=labelled,
                      tests={scene.shown: scene.tests for scene in config.scenes},
                      drawn=drawn_line(config, s.drawing),
                      timing_scene=timing_scene, count=len(board), results=results,
                      confined=not s.unconfined, args=config.submission.get("args", []))
    by_program = {e.program: e for e in s.entries}
    for _, row in board[board["kind"] == "program"].iterrows():
        # One report at a time, written and closed: a class of 200 holds no more open.
        text = submission_report(row, by_program[row["name"]], programs.get(row["name"], {}),
                                 grading)
        write_pages(reports / f"{row['name']}.md", text)
    board["name"] = board["name"].map(lambda n: by_program[n].shown if n in by_program else n)
    write_csv(board, out / "scoreboard.csv")
    class_page(board, labelled, {p: shown[p] for p in submissions}, scenes, out,
               f"The class: {title}", timed, engines[0] if engines else None,
               config.repetitions)
    total = sum(config.points.values())
    write_pages(out / "scoreboard.md", scoreboard_page(
        board, scenes, f"Scoreboard: {title}",
        f"Graded with {config.path} ({len(config.scenes)} judging scenes, then the timing "
        f"scene, seed {s.timing_seed[0]}; {drawn_line(config, s.drawing)}): each submission's "
        "verdict on every scene, its score of "
        f"{cell(float(total))} points, its rank and its report; the lab's references "
        f"({', '.join(timed_engines(config))}) "
        "are timed beside them."))
    return board


def own_windows(per_scene: pd.DataFrame, labelled: pd.DataFrame, timings: list,
                submissions: set[str], lab: set[str], declaration) -> pd.DataFrame:
    """per_scene with each submission's timing-scene row taken from its own timing window
    alone, so that its times beside the engines (vs_fastest_exact) are those of its node; the
    same rows where there is one window."""
    if len(timings) < 2:
        return per_scene
    own = []
    for timing in timings:
        rows = labelled[labelled["results"] == str(timing.directory)]
        mine = submissions & set(rows["engine"])
        if mine:
            verdicts = scene_verdicts(rows, mine | lab, declaration)
            own.append(verdicts[verdicts["name"].isin(mine)])
    if not own:
        return per_scene
    own = pd.concat(own, ignore_index=True)
    replaced = per_scene["name"].isin(own["name"]) & per_scene["scene"].isin(own["scene"])
    return pd.concat([per_scene[~replaced], own], ignore_index=True)


def exit_status(tool: str, step) -> int:
    """Runs step(): 0, or the grading's exit status for what stopped it, said in one line:
    2 bad input, psweep's own status, 1 a family that could not be drawn."""
    try:
        step()
    except InputError as err:
        print(f"{tool}: error: {err}", file=sys.stderr)
        return 2
    except SweepError as err:
        print(f"{tool}: error: {err}", file=sys.stderr)
        return err.status
    except DrawError as err:
        print(f"{tool}: error: {err}", file=sys.stderr)
        return 1
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description="Judge and time every submission of a folder: a scoreboard and a report "
                    "per submission.",
        epilog="Each entry of DIR not starting with '.' is a submission, run confined as "
               "`NAME < scene` with OMP_NUM_THREADS = T (docs/programs.md, \"Grading many "
               "submissions\"). Exit 0 when the grading ran, whatever the submissions did; "
               "2 on bad input.")
    parser.add_argument("submissions", metavar="DIR", help="folder of submissions, one "
                        "executable each")
    parser.add_argument("--out", default="results/grade", help="results folder "
                        "(default results/grade)")
    parser.add_argument("--config", default="configs/grade.json", help="judging scenes and "
                        "timing (default configs/grade.json)")
    parser.add_argument("--psweep", default="build/psweep", help="psweep to run "
                        "(default build/psweep)")
    parser.add_argument("--unconfined", action="store_true", help="run the submissions as you, "
                        "with your files, environment and network, where the sandbox cannot be "
                        "made (docs/programs.md, \"Confinement\")")
    args = parser.parse_args(argv)
    out = Path(args.out)
    graded = []
    status = exit_status("grade", lambda: graded.append(
        grade(args.submissions, out, args.config, args.psweep, args.unconfined)))
    if status:
        return status
    print(markdown_table(graded[0]), end="")
    print(f"grade: wrote {out / 'scoreboard.csv'}, {out / 'scoreboard.md'} and .html, "
          f"{out / 'class.md'} and .html, "
          f"{out / 'reports'}/NAME.md and .html, {out / 'grades.csv'} and "
          f"{out / 'gradescope'}/NAME/results.json", file=sys.stderr)
    return 0
