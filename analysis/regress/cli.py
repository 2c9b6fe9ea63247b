"""make regress / make regress-baseline: run the regression suite and compare with the baseline.

  /usr/bin/python3 -m analysis regress run [--build DIR] [--only instructions|wall]
      measures into results/regress/latest/, compares with results/baselines/regress/, prints the
      table, writes results/regress/report.md, appends results/regress/history.csv, looks for
      steps in the history and draws results/regress/plots/.
  /usr/bin/python3 -m analysis regress baseline [--build DIR]
      measures both parts, prints what changed against the previous baseline, and writes the
      new one (measurements.csv, meta.json, report.md) to results/baselines/regress/.
  /usr/bin/python3 -m analysis regress baseline --group NAME [--build DIR]
      measures that group alone (a new one, or one whose code changed on purpose) and puts its
      rows into the committed baseline in place of its old ones, every other row and the
      baseline's meta.json kept (which records the group's own commit and date under
      "groups_recorded_alone"); refused where this environment differs from the baseline's for
      a part the group measures, since its rows would then not compare with the rest.

Exit status: 0 nothing regressed, 1 something did (each named on stderr), 2 bad usage, a bad
suite file, a missing baseline or a build that cannot be run.
"""
from __future__ import annotations

import argparse
import copy
import json
import shutil
import sys
from pathlib import Path

import pandas as pd


from analysis.common.csv_out import write_csv
from analysis.regress.check import (PARTS, check_hashes, compare_part,
                                    environment_differences, instruction_spread, outcome,
                                    speed_difference)
from analysis.regress.report import (append_history, draw_history, history_rows,
                                     history_steps, text_table, write_report)
from analysis.regress.suite import (SuiteError, load_suite, measure,
                                    read_measurements)


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="Exit 0 nothing regressed, 1 a regression, 2 usage, "
                                            "config or build errors.")
    parser.add_argument("command", choices=["run", "baseline"])
    parser.add_argument("--build", default="build", help="CMake build holding psim and psweep")
    parser.add_argument("--config", default="configs/regression.json", help="the suite")
    parser.add_argument("--baseline", default="results/baselines/regress",
                        help="the committed baseline folder")
    parser.add_argument("--out", default="results/regress",
                        help="report.md, history.csv, plots/ and latest/ (the raw runs)")
    parser.add_argument("--only", choices=PARTS, help="run one part (CI: instructions)")
    parser.add_argument("--base-build", metavar="DIR",
                        help="compare with this build (make regress BASE=REF builds the base "
                             "commit there) measured here beside --build, interleaved, instead "
                             "of the committed baseline")
    parser.add_argument("--require-gate", action="store_true",
                        help="fail (exit 1) when the instruction counts could not be gated "
                             "against the baseline (CI: a gate that never bites guards nothing)")
    parser.add_argument("--group", metavar="NAME",
                        help="baseline: record this group alone into the committed baseline")
    parser.add_argument("--instruction-reps", type=int, metavar="N",
                        help="count each configuration N times and print the spread "
                             "(to check the instruction threshold)")
    args = parser.parse_args(argv)
    if args.instruction_reps is not None and args.instruction_reps < 1:
        parser.error("--instruction-reps: expected a positive integer")
    if args.group is not None and args.command != "baseline":
        parser.error("--group: only with baseline")
    return args


def compare(suite, baseline, baseline_meta, now, now_meta, parts, paired=False):
    """Comparisons, hash problems and each part's reasons not to gate. `paired`: the two were
    measured here in rounds (measure_against_base)."""
    gates, comparisons = {}, []
    for part in PARTS:
        if part not in parts:
            gates[part] = None
            continue
        why = environment_differences(baseline_meta, now_meta, part)
        if part == "wall" and not paired and not why:
            why = speed_difference(baseline, now, suite.thresholds)
        gates[part] = why
        comparisons += compare_part(baseline, now, part, suite.thresholds, why, paired)
    return gates, comparisons, check_hashes(baseline, now)


def print_gates(gates: dict) -> None:
    for part, why in gates.items():
        if why:
            print(f"regress: {part} reported, not gated: {'; '.join(why)}", file=sys.stderr)


def measure_against_base(suite, head: Path, base: Path, out: Path, parts, measure_one=measure):
    """Both builds on this machine, group by group: `base.rounds` rounds in which each build runs
    every configuration `base.repetitions` times, the builds' order alternating (base then head,
    head then base, ...), so that a round's runs of a configuration are seconds apart and whatever
    else the machine does then falls on both alike (paired_wall_verdict compares the rounds'
    minima). Returns (base frame, base meta, head frame, head meta); `rep` is the round."""
    rounds = {"instructions": suite.instructions["repetitions"], "wall": suite.base_rounds}
    single = copy.deepcopy(suite)
    single.wall.update(repetitions=suite.base_repetitions, warmup=0)
    single.instructions.update(repetitions=1)
    frames, metas = {"base": [], "head": []}, {}
    for part in parts:
        for group in (g for g in suite.groups if part in g.parts):
            one = copy.copy(single)
            one.groups = [group]
            for r in range(rounds[part]):
                order = (("base", base), ("head", head))
                for name, build in order if r % 2 == 0 else order[::-1]:
                    folder = out / name / f"{part}-{group.name}-{r}"
                    frame, meta = measure_one(one, build, folder, (part,))
                    frames[name].append(frame.assign(rep=r))
                    metas.setdefault(name, {}).update(meta)
    return (pd.concat(frames["base"], ignore_index=True), metas["base"],
            pd.concat(frames["head"], ignore_index=True), metas["head"])


def run(args, suite) -> int:
    out = Path(args.out)
    parts = (args.only,) if args.only else PARTS
    if args.base_build:
        baseline, baseline_meta, now, now_meta = measure_against_base(
            suite, Path(args.build), Path(args.base_build), out / "latest", parts)
    else:
        baseline_dir = Path(args.baseline)
        if not (baseline_dir / "measurements.csv").exists():
            raise SuiteError(f"no baseline in {baseline_dir}: record one with make "
                             "regress-baseline")
        baseline, baseline_meta = read_measurements(baseline_dir)
        now, now_meta = measure(suite, Path(args.build), out / "latest", parts,
                                args.instruction_reps)
    if args.instruction_reps:
        print(instruction_spread(now).to_string(index=False))
    gates, comparisons, hashes = compare(suite, baseline, baseline_meta, now, now_meta, parts,
                                         paired=bool(args.base_build))
    status, reasons = outcome(comparisons, hashes)

    history = append_history(out / "history.csv",
                             history_rows(comparisons, now_meta, baseline_meta))
    cpu = now_meta.get("machine", {}).get("cpu_model")
    steps = history_steps(history, cpu, baseline_meta.get("date"))
    plots = draw_history(history, cpu, suite.thresholds, out / "plots")
    write_report(out / "report.md", baseline_meta, now_meta, gates, comparisons, hashes, steps,
                 reasons, plots, suite.thresholds, paired=bool(args.base_build))

    print(text_table(comparisons))
    print_gates(gates)
    if args.require_gate and "instructions" in parts and gates["instructions"]:
        print("regress: FAILED: the instruction gate did not bite (--require-gate): "
              f"{'; '.join(gates['instructions'])}; record a baseline in this environment "
              "(make regress-baseline) or count in the baseline's", file=sys.stderr)
        status = 1
    for step in steps:
        print(f"regress: history: {step}", file=sys.stderr)
    if status:
        print("regress: REGRESSION:", file=sys.stderr)
        for reason in reasons:
            print(f"  {reason}", file=sys.stderr)
    else:
        print("regress: no regression", file=sys.stderr)
    print(f"regress: report in {out / 'report.md'} and {out / 'report.html'}", file=sys.stderr)
    return status


def record_baseline(args, suite) -> int:
    baseline_dir = Path(args.baseline)
    fresh = Path(args.out) / "new-baseline"
    now, now_meta = measure(suite, Path(args.build), fresh, PARTS)
    if (baseline_dir / "measurements.csv").exists():
        old, old_meta = read_measurements(baseline_dir)
        gates, comparisons, hashes = compare(suite, old, old_meta, now, now_meta, PARTS)
        print("Against the previous baseline:")
        print(text_table(comparisons))
        print_gates(gates)
        for h in hashes:
            print(f"regress: {h.label} ({h.part}): final state {h.verdict}: {h.baseline} -> "
                  f"{h.now}", file=sys.stderr)
        write_report(fresh / "report.md", old_meta, now_meta, gates, comparisons, hashes, [],
                     [], [], suite.thresholds)
    else:
        print("regress: no previous baseline; recording the first", file=sys.stderr)
    baseline_dir.mkdir(parents=True, exist_ok=True)
    for name in ("measurements.csv", "meta.json", "report.md"):
        if (fresh / name).exists():
            shutil.copyfile(fresh / name, baseline_dir / name)
    print(f"regress: new baseline in {baseline_dir} (commit it)", file=sys.stderr)
    return 0


def record_group(args, suite) -> int:
    """make regress-baseline GROUP=NAME: one group measured and put into the committed baseline."""
    baseline_dir = Path(args.baseline)
    group = next((g for g in suite.groups if g.name == args.group), None)
    if group is None:
        raise SuiteError(f"{suite.file}: no group {args.group!r} (groups: "
                         f"{', '.join(g.name for g in suite.groups)})")
    old, old_meta = read_measurements(baseline_dir)
    one = copy.copy(suite)
    one.groups = [group]
    now, now_meta = measure(one, Path(args.build), Path(args.out) / "new-baseline", group.parts)
    for part in group.parts:
        if why := environment_differences(old_meta, now_meta, part):
            raise SuiteError(f"group {group.name}: its {part} would not compare with the "
                             f"baseline's other rows: {'; '.join(why)}; record the whole "
                             "baseline instead (make regress-baseline)")
    rows = pd.concat([old[old["group"] != group.name], now], ignore_index=True)
    write_csv(rows, baseline_dir / "measurements.csv")
    recorded = [r for r in old_meta.get("groups_recorded_alone", []) if r["group"] != group.name]
    old_meta["groups_recorded_alone"] = recorded + [
        {"group": group.name, "parts": list(group.parts), "date": now_meta.get("date"),
         "git": now_meta.get("git")}]
    (baseline_dir / "meta.json").write_text(json.dumps(old_meta, indent=2) + "\n")
    print(now[["label", "part", "metric", "value"]].to_string(index=False))
    print(f"regress: group {group.name} recorded into {baseline_dir}, the other rows kept "
          "(commit it)", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    args = parse_args(argv)
    try:
        suite = load_suite(args.config)
        if args.command == "run":
            return run(args, suite)
        return record_group(args, suite) if args.group else record_baseline(args, suite)
    except SuiteError as err:
        print(f"regress: {err}", file=sys.stderr)
        return 2

