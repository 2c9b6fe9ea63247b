#!/usr/bin/python3
"""Compare two sweeps (`make compare A=DIR B=DIR`): two commits, two machines, two flag sets.

For every configuration (engine, parameters and T) present in both results folders: the minimum
wall time in A and in B, their ratio B / A (above 1: B is slower), and whether the difference is
beyond the repetitions' spread. The test follows google/benchmark's tools/compare.py: a two-sided
Mann-Whitney U test on the two sets of repetitions, which assumes nothing about the shape of the
noise (timings on a shared machine are skewed: noise only adds time). It needs at least
MIN_REPS_FOR_U repetitions on each side: with 5 against 5 the smallest possible p-value is
2/252 = 0.008; with fewer the verdict falls back to whether the two min-max ranges overlap, and
with a single repetition there is no spread to judge by.

Writes OUT/compare.csv (full precision), OUT/compare.md (provenance of both sweeps, then the
table) and OUT/ratio.png|svg; prints the markdown to stdout. Exit 2 on bad input.

The computing (compare_runs, compare_samples) is pure and used by other tools (regression
checks) as a library; drawing and files are only in main().
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from analysis.csv_out import write_csv  # noqa: E402
from analysis.load import InputError, Results, load_results  # noqa: E402
from analysis.stats import RUN_KEYS, aggregate, varying  # noqa: E402

# google/benchmark's defaults: 5 repetitions before the U test is trusted, alpha 0.05.
MIN_REPS_FOR_U = 5
ALPHA = 0.05

VERDICTS = ("slower", "faster", "same", "unknown", "only in A", "only in B")


def compare_samples(a, b, alpha: float = ALPHA) -> tuple[str, float, str]:
    """Judge two samples of wall times: returns (test, p_value, verdict).

    test is "U test" (both sides have >= MIN_REPS_FOR_U values), "ranges" (2 or more each: the
    min-max ranges overlap or not) or "none" (a single value: no spread to compare against).
    verdict is "slower" / "faster" (b against a, beyond the spread) or "same"; "unknown" for
    test "none". p_value is NaN unless the U test ran."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if min(len(a), len(b)) >= MIN_REPS_FOR_U:
        from scipy.stats import mannwhitneyu
        p = float(mannwhitneyu(a, b, alternative="two-sided").pvalue)
        if p >= alpha:
            return "U test", p, "same"
        # The U test says the distributions differ; the medians say which way.
        return "U test", p, "slower" if np.median(b) > np.median(a) else "faster"
    if min(len(a), len(b)) >= 2:
        if b.min() > a.max():
            return "ranges", math.nan, "slower"
        if b.max() < a.min():
            return "ranges", math.nan, "faster"
        return "ranges", math.nan, "same"
    return "none", math.nan, "unknown"


def compare_runs(a_runs: pd.DataFrame, b_runs: pd.DataFrame,
                 alpha: float = ALPHA) -> pd.DataFrame:
    """One row per configuration (CONFIG_PARAMS + T) found in either sweep's ok runs: reps and
    wall_s_min on both sides, ratio = B / A of the minima, test, p_value, verdict. Rows present
    on one side only get verdict "only in A" / "only in B" and empty values for the other."""
    a_walls = aggregate(a_runs, "wall_s")
    b_walls = aggregate(b_runs, "wall_s")
    keep = RUN_KEYS + ["reps", "wall_s_min", "wall_s_median", "wall_s_max"]
    table = a_walls[keep].merge(b_walls[keep], on=RUN_KEYS, how="outer", suffixes=("_a", "_b"),
                                indicator=True)
    a_samples = samples(a_runs)
    b_samples = samples(b_runs)
    rows = []
    for _, row in table.iterrows():
        key = tuple(row[k] for k in RUN_KEYS)
        if row["_merge"] == "left_only":
            test, p, verdict = "none", math.nan, "only in A"
        elif row["_merge"] == "right_only":
            test, p, verdict = "none", math.nan, "only in B"
        else:
            test, p, verdict = compare_samples(a_samples[normal_key(key)],
                                               b_samples[normal_key(key)], alpha)
        rows.append(dict(test=test, p_value=p, verdict=verdict))
    out = pd.concat([table.drop(columns="_merge").reset_index(drop=True),
                     pd.DataFrame(rows, columns=["test", "p_value", "verdict"])], axis=1)
    for side in ("a", "b"):
        out[f"reps_{side}"] = out[f"reps_{side}"].fillna(0).astype(int)
    out["ratio"] = out["wall_s_min_b"] / out["wall_s_min_a"]
    columns = RUN_KEYS + ["reps_a", "reps_b", "wall_s_min_a", "wall_s_min_b", "ratio",
                          "wall_s_median_a", "wall_s_median_b", "wall_s_max_a", "wall_s_max_b",
                          "test", "p_value", "verdict"]
    return out[columns].sort_values(["engine", "N", "T"], kind="stable").reset_index(drop=True)


def normal_key(key: tuple) -> tuple:
    # NaN != NaN, so empty parameters (G for brute) would never look a sample up; None does.
    return tuple(None if isinstance(v, float) and math.isnan(v) else v for v in key)


def samples(runs: pd.DataFrame) -> dict[tuple, np.ndarray]:
    ok = runs[(runs["status"] == "ok") & runs["wall_s"].notna()]
    return {normal_key(key if isinstance(key, tuple) else (key,)): group["wall_s"].to_numpy()
            for key, group in ok.groupby(RUN_KEYS, dropna=False, sort=False)}


def provenance_line(label: str, results: Results) -> str:
    """Commit, machine and date of one sweep on one line, from meta.json."""
    meta = results.meta
    git = meta.get("git") if isinstance(meta.get("git"), dict) else {}
    machine = meta.get("machine") if isinstance(meta.get("machine"), dict) else {}
    commit = str(git.get("commit") or "unknown commit")[:12]
    if git.get("dirty"):
        commit += " (dirty)"
    parts = [f"commit {commit}"]
    host = ", ".join(str(machine[k]) for k in ("hostname", "cpu_model") if machine.get(k))
    if host:
        parts.append(host)
    if results.cores:
        parts.append(f"{results.cores} CPUs")
    if meta.get("date"):
        parts.append(str(meta["date"]))
    return f"- **{label}** `{results.directory}`: " + ", ".join(parts)


def summary_line(table: pd.DataFrame) -> str:
    counts = table["verdict"].value_counts()
    both = table[~table["verdict"].isin(["only in A", "only in B"])]
    text = f"{len(both)} configurations in both sweeps: " + ", ".join(
        f"{int(counts.get(v, 0))} {v}" for v in ("slower", "faster", "same", "unknown")
        if counts.get(v, 0))
    if len(both) and both["ratio"].notna().any():
        ratios = both["ratio"].dropna()
        text += (f". Geometric mean of the ratios B / A: "
                 f"{math.exp(np.log(ratios).mean()):.3f}")
    only = {v: int(counts.get(v, 0)) for v in ("only in A", "only in B") if counts.get(v, 0)}
    if only:
        text += ". Not compared: " + ", ".join(f"{n} {v}" for v, n in only.items())
    return text + "."


def label_columns(table: pd.DataFrame) -> list[str]:
    """The parameters that differ between rows: what names a row in the table and the plot."""
    return varying(table, RUN_KEYS)


def shown_table(table: pd.DataFrame) -> pd.DataFrame:
    """The columns a reader needs: the parameters that differ between rows, then the result."""
    shown = table[label_columns(table) + ["reps_a", "reps_b", "wall_s_min_a", "wall_s_min_b", "ratio",
                          "test", "p_value", "verdict"]]
    return shown.rename(columns={"reps_a": "reps A", "reps_b": "reps B",
                                 "wall_s_min_a": "wall s min A", "wall_s_min_b": "wall s min B",
                                 "ratio": "B / A", "p_value": "p"})


def markdown(a: Results, b: Results, table: pd.DataFrame) -> str:
    from analysis.markdown import markdown_table
    fixed = [c for c in RUN_KEYS if c not in label_columns(table)
             and table[c].notna().any()]
    text = ["# Sweep comparison: B against A\n", provenance_line("A", a),
            provenance_line("B", b), "",
            "`B / A` is the ratio of the minimum wall times (above 1: B is slower). The "
            f"verdict is beyond the spread of the repetitions: a two-sided Mann-Whitney U test "
            f"(p < {ALPHA}) where both sides have at least {MIN_REPS_FOR_U} repetitions, else "
            "whether the min-max ranges overlap; one repetition has no spread (`unknown`).\n",
            summary_line(table) + "\n"]
    if fixed:
        first = table.iloc[0]
        text.append("Same in every row: " + ", ".join(f"{c}={fmt_value(first[c])}"
                                                      for c in fixed) + ".\n")
    text.append(markdown_table(shown_table(table)))
    return "\n".join(text)


def fmt_value(value) -> str:
    from analysis.figures import fmt
    return fmt(value)


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog="compare.py",
        description="Compare two psweep results folders configuration by configuration.",
        epilog="Writes OUT/compare.csv, OUT/compare.md and OUT/ratio.png|svg and prints the "
               "table. Exit 2 on bad input.")
    parser.add_argument("a", metavar="A", help="the reference results folder (e.g. the old commit)")
    parser.add_argument("b", metavar="B", help="the results folder compared against A")
    parser.add_argument("--out", metavar="OUT",
                        help="output folder (default: results/compare/<A>-vs-<B>)")
    parser.add_argument("--no-svg", action="store_true", help="write PNG only")
    return parser.parse_args(argv)


def default_out(a: Path, b: Path) -> Path:
    a_name, b_name = a.resolve().name, b.resolve().name
    if a_name == b_name:  # results/x/threads against results/y/threads
        a_name, b_name = a.resolve().parent.name, b.resolve().parent.name
    return Path("results") / "compare" / f"{a_name}-vs-{b_name}"


def main(argv=None) -> int:
    args = parse_args(argv)
    try:
        a, b = load_results(args.a), load_results(args.b)
        table = compare_runs(a.runs, b.runs)
        if table["verdict"].isin(["only in A", "only in B"]).all():
            raise InputError(f"{args.a} and {args.b} have no configuration in common "
                             f"(engine, parameters and T must all match)")
    except InputError as err:
        print(f"compare: error: {err}", file=sys.stderr)
        return 2
    from analysis import figures
    from analysis.figures_hpc import plot_ratios
    if args.no_svg:
        figures.FORMATS = ("png",)
    out = Path(args.out) if args.out else default_out(Path(args.a), Path(args.b))
    out.mkdir(parents=True, exist_ok=True)
    write_csv(table, out / "compare.csv")
    text = markdown(a, b, table)
    plot_ratios(table, label_columns(table), out / "ratio",
                        f"{Path(args.a).name} (A)", f"{Path(args.b).name} (B)")
    (out / "compare.md").write_text(text + "\n![ratios](ratio.png)\n")
    print(text)
    print(f"compare: wrote {out / 'compare.csv'}, {out / 'compare.md'}, {out / 'ratio.png'}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
