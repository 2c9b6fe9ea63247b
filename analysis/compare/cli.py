"""Compare two sweeps (`make compare A=DIR B=DIR`): two commits, two machines, two flag sets.

For every configuration (engine, parameters and T) present in both results folders: the minimum
wall time in A and in B, their ratio B / A (above 1: B is slower), and whether the difference is
beyond the repetitions' spread. The test follows google/benchmark's tools/compare.py: a two-sided
Mann-Whitney U test on the two sets of repetitions, which assumes nothing about the shape of the
noise (timings on a shared machine are skewed: noise only adds time). It needs at least
MIN_REPS_FOR_U repetitions on each side: with 5 against 5 the smallest possible p-value is
2/252 = 0.008. With fewer, a difference counts only when the two min-max ranges are apart by
more than either is wide; otherwise the verdict is "not enough repetitions to tell" (a single
repetition has no spread to judge by).

Writes OUT/compare.csv (full precision), OUT/compare.md (provenance of both sweeps, then the
table), OUT/compare.html (the same as one page) and OUT/ratio.png|svg; prints the markdown to
stdout. Exit 2 on bad input.

compare_runs is pure (the test itself, compare_samples, is in common/stats.py: make regress
judges wall times with it too); drawing and files are only in plot_ratios() and main().
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from analysis.common.csv_out import write_csv
from analysis.common.labels import fmt, series_label
from analysis.common.load import InputError, Results, load_results
from analysis.common.markdown import markdown_table
from analysis.common.page import write_pages
from analysis.common.stats import (ALPHA, MIN_REPS_FOR_U, RUN_KEYS, TOO_FEW, aggregate,
                                   compare_samples,
                                   varying)

VERDICTS = ("slower", "faster", "same", TOO_FEW, "only in A", "only in B")


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
        f"{int(counts.get(v, 0))} {v}" for v in ("slower", "faster", "same", TOO_FEW)
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
    fixed = [c for c in RUN_KEYS if c not in label_columns(table)
             and table[c].notna().any()]
    text = ["# Sweep comparison: B against A\n", provenance_line("A", a),
            provenance_line("B", b), "",
            "`B / A` is the ratio of the minimum wall times (above 1: B is slower). The "
            f"verdict is beyond the spread of the repetitions: a two-sided Mann-Whitney U test "
            f"(p < {ALPHA}) where both sides have at least {MIN_REPS_FOR_U} repetitions, else "
            "whether the min-max ranges are apart by more than either is wide (otherwise "
            f"`{TOO_FEW}`, as with a single repetition).\n",
            summary_line(table) + "\n"]
    if fixed:
        first = table.iloc[0]
        text.append("Same in every row: " + ", ".join(f"{c}={fmt(first[c])}"
                                                      for c in fixed) + ".\n")
    text.append(markdown_table(shown_table(table)))
    return "\n".join(text)


VERDICT_COLOURS = {"slower": "C3", "faster": "C2", "same": "0.6", TOO_FEW: "0.85"}


def plot_ratios(table: pd.DataFrame, label_columns: list[str], stem: Path, a_name: str,
                b_name: str) -> Path | None:
    """One horizontal bar per configuration from 1 to its ratio B / A on a log axis (2x slower
    and 2x faster look alike), coloured by the verdict."""
    from analysis.common import hover
    from analysis.common.figures import plt, readable_log, save

    rows = table.dropna(subset=["ratio"]).reset_index(drop=True)
    if rows.empty:
        return None
    height = min(30.0, 1.6 + 0.28 * len(rows))
    fig, ax = plt.subplots(figsize=(8.5, height))
    y = np.arange(len(rows))
    colours = [VERDICT_COLOURS.get(v, "0.6") for v in rows["verdict"]]
    ax.barh(y, rows["ratio"] - 1, left=1, color=colours, height=0.7)
    hover.tag_rows(ax, rows["ratio"], y, rows, value="x")
    ax.axvline(1, color="0.2", linewidth=1)
    ax.set_yticks(y)
    ax.set_yticklabels([series_label(row, label_columns) for _, row in rows.iterrows()],
                       fontsize=7 if len(rows) > 20 else 9)
    ax.invert_yaxis()
    spread = max(float(np.abs(np.log(rows["ratio"])).max()), np.log(1.1))
    ax.set_xlim(np.exp(-1.15 * spread), np.exp(1.15 * spread))
    ax.set_xlabel(f"wall time ratio {b_name} / {a_name} (min over repetitions)")
    readable_log(ax, "x")
    present = [v for v in VERDICT_COLOURS if v in set(rows["verdict"])]
    handles = [plt.Rectangle((0, 0), 1, 1, color=VERDICT_COLOURS[v]) for v in present]
    ax.legend(handles, present, title="beyond the spread?", loc="upper left",
              bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    ax.set_title(f"{b_name} against {a_name}: right of 1 is slower")
    return save(fig, stem)


def parse_args(argv):
    parser = argparse.ArgumentParser(
        description="Compare two psweep results folders configuration by configuration.",
        epilog="Writes OUT/compare.csv, OUT/compare.md, OUT/compare.html and OUT/ratio.png|svg and "
               "prints the "
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
    # After validation: matplotlib costs a second, bad input should not wait for it.
    from analysis.common import figures
    if args.no_svg:
        figures.FORMATS = ("png",)
    out = Path(args.out) if args.out else default_out(Path(args.a), Path(args.b))
    out.mkdir(parents=True, exist_ok=True)
    write_csv(table, out / "compare.csv")
    text = markdown(a, b, table)
    plot_ratios(table, label_columns(table), out / "ratio", f"{Path(args.a).name} (A)",
                f"{Path(args.b).name} (B)")
    page = write_pages(out / "compare.md", text + "\n![ratios](ratio.png)\n")
    print(text)
    print(f"compare: wrote {out / 'compare.csv'}, {out / 'compare.md'}, {page}, "
          f"{out / 'ratio.png'}", file=sys.stderr)
    return 0

