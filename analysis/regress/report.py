"""make regress: the printed table, report.md and report.html, history.csv, the history's steps
and its plots.

Computing stays in check.py and changepoint.py; here are only formatting, the history file and
drawing (the lab's figures.save, so each history point's tooltip in report.html names its commit).
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib.dates
import pandas as pd

from analysis.common import hover
from analysis.common.csv_out import write_csv
from analysis.common.figures import plt, save
from analysis.common.markdown import markdown_table as frame_table
from analysis.common.page import write_pages
from analysis.regress.changepoint import change_points
from analysis.regress.check import Comparison, HashCheck, Thresholds

HISTORY_COLUMNS = ["run_date", "commit", "commit_date", "dirty", "cpu_model", "baseline_date",
                   "part", "label", "config_id", "metric", "value", "baseline", "change",
                   "verdict"]

# Noise floors of the step detection, relative to the level: instruction counts repeat to
# better than 1e-4, so a tenth of the 1% gate is a real step; wall minima on a shared machine
# wander by a percent between quiet nights.
STEP_FLOOR = {"instructions": 0.001, "wall": 0.01}


def format_value(metric: str, value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if metric == "instructions":
        return f"{value / 1e6:,.2f} M"
    return f"{value:.4f} s"


def verdict_text(c: Comparison) -> str:
    if c.verdict == "ok" or c.verdict == "new":
        return c.verdict
    text = c.verdict.upper() if c.fails else c.verdict
    return text if c.gated else f"{text} (not gated)"


def table_rows(comparisons: list[Comparison]) -> list[list[str]]:
    return [[c.label, c.metric, format_value(c.metric, c.baseline), format_value(c.metric, c.now),
             "-" if c.change is None else f"{c.change:+.2%}", verdict_text(c)]
            for c in comparisons]


HEADER = ["configuration", "metric", "baseline", "now", "change", "verdict"]


def text_table(comparisons: list[Comparison]) -> str:
    rows = [HEADER] + table_rows(comparisons)
    widths = [max(len(r[i]) for r in rows) for i in range(len(HEADER))]
    right = {2, 3, 4}
    lines = ["  ".join(cell.rjust(w) if i in right else cell.ljust(w)
                       for i, (cell, w) in enumerate(zip(row, widths))).rstrip()
             for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    return frame_table(pd.DataFrame(rows, columns=header, dtype=str))


def worst_first(comparisons: list[Comparison]) -> list[Comparison]:
    """Gated failures, then reported-only regressions, then the rest, each in suite order: the
    verdicts a reader must act on are at the top."""
    def rank(c: Comparison) -> int:
        return 0 if c.fails else 1 if c.verdict in ("regressed", "failed") else 2
    return sorted(comparisons, key=rank)


def describe_run(meta: dict) -> str:
    git, build, machine = meta.get("git", {}), meta.get("build", {}), meta.get("machine", {})
    dirty = " (uncommitted changes)" if git.get("dirty") else ""
    return (f"commit `{str(git.get('commit'))[:12]}`{dirty} of {git.get('commit_date')}, run "
            f"{meta.get('date')}; {machine.get('cpu_model')}, {machine.get('online_cpus')} CPUs "
            f"({machine.get('physical_cores')} cores); {build.get('compiler')} "
            f"`{build.get('flags')}`; {meta.get('valgrind') or 'no valgrind'}")


def write_report(path: Path, baseline_meta: dict, now_meta: dict, gates: dict,
                 comparisons: list[Comparison], hashes: list[HashCheck], steps: list[str],
                 reasons: list[str], plots: list[Path], th: Thresholds,
                 paired: bool = False) -> None:
    """gates: part -> list of reasons it does not gate (empty: it gates; None: not run). Writes
    report.md and report.html; the last run's verdicts come first, worst first."""
    out = ["# Regression check", ""]
    out.append(f"**{'REGRESSED' if reasons else 'No regression'}**" +
               (": " + "; ".join(reasons) if reasons else "") + "\n")
    out.append("## Verdicts\n")
    ordered = worst_first(comparisons)
    rows = [r + [c.detail] for r, c in zip(table_rows(ordered), ordered)]
    out.append(markdown_table(HEADER + ["detail"], rows))
    out.append("## Runs compared\n")
    out += [f"- now: {describe_run(now_meta)}", f"- baseline: {describe_run(baseline_meta)}"]
    if now_meta.get("build", {}).get("flags") != baseline_meta.get("build", {}).get("flags"):
        out.append(f"- **build flags differ**: baseline `{baseline_meta.get('build', {}).get('flags')}`,"
                   f" now `{now_meta.get('build', {}).get('flags')}` (compared all the same: "
                   "a build's flags are part of what is checked)")
    out.append("")
    out.append("## Gates\n")
    for part, why in gates.items():
        if why is None:
            out.append(f"- {part}: not run")
        elif why:
            out.append(f"- {part}: **reported, not gated**: {'; '.join(why)}")
        else:
            rule = (f"gated at {th.instructions:.1%} of the baseline's count" if part == "instructions"
                    else f"gated: the median of the rounds' head/base ratios beyond "
                         f"{th.wall_rel:.0%} and signed-rank p < {th.alpha:g}" if paired
                    else f"gated: a change of the minimum beyond max({th.wall_rel:.0%}, "
                         f"{th.wall_mads:g} MADs) and U test p < {th.alpha:g}")
            out.append(f"- {part}: {rule}")
    out.append("- state hashes: always checked; a changed final state is a correctness "
               "regression\n")
    out.append("## Results (state hashes)\n")
    if hashes:
        out.append(markdown_table(["configuration", "part", "baseline", "now", "verdict"],
                                  [[h.label, h.part, h.baseline, h.now, h.verdict.upper()]
                                   for h in hashes]))
    else:
        out.append("Every configuration ended in the baseline's final state.\n")
    out.append("## History: steps since the baseline\n")
    out.append("Binary segmentation over history.csv (advisory: it does not change the exit "
               "status).\n")
    out.append("\n".join(f"- {s}" for s in steps) + "\n" if steps else "_(none)_\n")
    if plots:
        out.append("## History per configuration\n")
        out.append("Instructions and wall time against commit date; the band is the baseline "
                   "plus or minus the gate's threshold, a dashed red line a step found in the "
                   "history.\n")
        out += [f"![{p.stem}](plots/{p.name})\n" for p in plots]
    write_pages(path, "\n".join(out))


def history_rows(comparisons: list[Comparison], meta: dict, baseline_meta: dict) -> pd.DataFrame:
    git = meta.get("git", {})
    rows = [{"run_date": meta.get("date"), "commit": git.get("commit"),
             "commit_date": git.get("commit_date"), "dirty": git.get("dirty"),
             "cpu_model": meta.get("machine", {}).get("cpu_model"),
             "baseline_date": baseline_meta.get("date"), "part": c.part, "label": c.label,
             "config_id": c.config_id, "metric": c.metric, "value": c.now,
             "baseline": c.baseline, "change": c.change, "verdict": c.verdict}
            for c in comparisons if c.now is not None]
    return pd.DataFrame(rows, columns=HISTORY_COLUMNS)


def append_history(path: Path, rows: pd.DataFrame) -> pd.DataFrame:
    """Appends and returns the whole history."""
    if path.exists():
        history = pd.read_csv(path, dtype={"config_id": str, "commit": str})
        history = pd.concat([history, rows], ignore_index=True)
    else:
        history = rows
    path.parent.mkdir(parents=True, exist_ok=True)
    write_csv(history, path)
    return history


def series(history: pd.DataFrame, cpu_model: str | None):
    """Each (part, label, config_id) series on this machine, in commit then run order."""
    same = history[history["cpu_model"] == cpu_model] if cpu_model else history
    same = same.sort_values(["commit_date", "run_date"], kind="stable")
    return same.groupby(["part", "label", "config_id"], sort=False)


def history_steps(history: pd.DataFrame, cpu_model: str | None, since: str | None) -> list[str]:
    """Steps in each series that happened after `since` (the baseline's date): older ones are
    already in the baseline."""
    found = []
    for (part, lab, _), rows in series(history, cpu_model):
        values = rows["value"].astype(float).to_numpy()
        for step in change_points(values, rel_floor=STEP_FLOOR[part]):
            at = rows.iloc[step.index]
            if since and str(at["run_date"]) <= since:
                continue
            found.append(f"{lab} {rows['metric'].iloc[0]}: step of {step.change:+.2%} at commit "
                         f"`{str(at['commit'])[:12]}` ({at['commit_date']}), "
                         f"{format_value(rows['metric'].iloc[0], step.before)} -> "
                         f"{format_value(rows['metric'].iloc[0], step.after)}")
    return found


def slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_")


def draw_history(history: pd.DataFrame, cpu_model: str | None, th: Thresholds,
                 folder: Path) -> list[Path]:
    """One PNG per configuration: instructions and wall time against commit date, the baseline
    band (baseline +- the gate's threshold), steps as dashed lines; each point tagged with its
    commit and run for report.html."""
    folder.mkdir(parents=True, exist_ok=True)
    by_label: dict[str, dict] = {}
    for (part, lab, _), rows in series(history, cpu_model):
        by_label.setdefault(lab, {})[part] = rows  # the newest config_id of a label wins
    written = []
    for lab, parts in sorted(by_label.items()):
        fig, axes = plt.subplots(len(parts), 1, figsize=(7, 2.6 * len(parts)), squeeze=False)
        for ax, (part, rows) in zip(axes[:, 0], sorted(parts.items())):
            x = pd.to_datetime(rows["commit_date"], utc=True, errors="coerce")
            scale = 1e6 if part == "instructions" else 1.0
            y = rows["value"].astype(float) / scale
            ax.plot(x, y, "o-", ms=3, lw=1)
            hover.tag(ax, matplotlib.dates.date2num(x), y,
                      [f"{lab}: commit {str(r.commit)[:12]} of {r.commit_date}, run {r.run_date}"
                       for r in rows.itertuples()])
            base = rows["baseline"].dropna()
            if not base.empty:
                b = float(base.iloc[-1]) / scale
                width = th.instructions if part == "instructions" else th.wall_rel
                ax.axhspan(b * (1 - width), b * (1 + width), color="tab:green", alpha=0.15,
                           label=f"baseline +-{width:.0%}")
                ax.axhline(b, color="tab:green", lw=0.8)
                ax.legend(loc="best")
            for step in change_points(rows["value"].astype(float).to_numpy(),
                                      rel_floor=STEP_FLOOR[part]):
                ax.axvline(x.iloc[step.index], color="tab:red", ls="--", lw=1)
            unit = "instructions (M)" if part == "instructions" else f"{rows['metric'].iloc[0]} min (s)"
            ax.set_ylabel(unit)
        axes[0, 0].set_title(lab)
        axes[-1, 0].set_xlabel("commit date")
        fig.autofmt_xdate()
        written.append(save(fig, folder / slug(lab), formats=("png",)))
    return written
