"""Drawing only: every function takes already-computed tables and writes <stem>.png and
<stem>.svg, returning the PNG path (or None when the data for that plot is absent, e.g.
hardware counters on a VM). No statistics are computed here beyond choosing what to draw.

Conventions, so all plots read alike: x is the thread count T with a tick at every measured T;
a dashed grey vertical line marks the machine's core count and the area right of it is shaded
as oversubscribed; one colour+marker per series, and one line style per engine where engines
vary, so a series is told apart without colour; the legend names only the parameters that vary;
constant parameters go in the title. Every point is tagged with its configuration for
report.html's tooltips (hover.py).
"""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd

from analysis.common import hover
from analysis.common.figures import MARKERS, engine_styles, plt, readable_log, save
from analysis.common.labels import SHORT, axis_label, engine_name, fmt, series_label
from analysis.common.load import CONFIG_PARAMS
from analysis.common.stats import varying
from analysis.plots.fits import fit_power_law, scaling_series, unaffected

MAX_SERIES = 10  # beyond this a legend stops being readable; the rest is in speedup.csv


# ---------------------------------------------------------------- labels

def context(table: pd.DataFrame, exclude=()) -> str:
    """The parameters that are constant in `table`, for the title."""
    keep = [c for c in ["engine", "N", "L", "r", "S", "slow_factor", "G", "pin"]
            if c not in exclude and c in table.columns and table[c].nunique(dropna=True) == 1]
    return ", ".join(f"{SHORT.get(c, c)}="
                     + (engine_name(table) if c == "engine" else fmt(table[c].dropna().iloc[0]))
                     for c in keep)


def time_unit(seconds) -> tuple[str, float]:
    """The unit that puts the largest of `seconds` between 1 and 1000: ("ms", 1e3) for 0.05 s,
    so ticks read 50 instead of 0.05 and 0.00005 becomes 50 µs."""
    largest = float(pd.Series(seconds).abs().max())
    if not np.isfinite(largest) or largest >= 1:
        return "s", 1.0
    if largest >= 1e-3:
        return "ms", 1e3
    return "µs", 1e6


# ---------------------------------------------------------------- thread-count plots

def series_columns(table: pd.DataFrame) -> list[str]:
    return varying(table, [c for c in CONFIG_PARAMS])


def mark_cores(ax, cores: int | None, t_max: float) -> None:
    if not cores:
        return
    ax.axvline(cores, color="0.4", linestyle="--", linewidth=1, label=f"{cores} cores")
    if t_max > cores:
        ax.axvspan(cores, t_max + 0.5, color="0.85", alpha=0.5, zorder=0,
                   label="oversubscribed")


def thread_axis(ax, ts) -> None:
    ts = sorted(set(int(t) for t in ts))
    ax.set_xticks(ts)
    ax.set_xlim(0.5, max(ts) + 0.5)
    ax.set_xlabel("threads T")


def draw_series(ax, table, y, columns, yerr_low=None, yerr_high=None) -> int:
    """One line per combination of `columns`; returns how many were drawn."""
    drawn = 0
    # A single key as a scalar, not a one-element list: pandas changes the key type for lists.
    by = columns[0] if len(columns) == 1 else columns
    groups = list(table.groupby(by, dropna=False, sort=True)) if columns else [((), table)]
    if len(groups) > MAX_SERIES:
        note_truncated(ax, len(groups))
    line_style = engine_styles(table)
    for i, (key, group) in enumerate(groups[:MAX_SERIES]):
        group = group.dropna(subset=[y]).sort_values("T")
        if group.empty:
            continue
        label = series_label(group.iloc[0], columns)
        style = dict(marker=MARKERS[i % len(MARKERS)], markersize=5, linewidth=1.5,
                     label=label, color=f"C{i % 10}",
                     linestyle=line_style.get(group["engine"].iloc[0], "-")
                     if "engine" in group else "-")
        if yerr_low is not None:
            err = [group[y] - group[yerr_low], group[yerr_high] - group[y]]
            # Nudge each series sideways a little so error bars at the same T stay apart.
            dodge = 0.06 * (i - (min(len(groups), MAX_SERIES) - 1) / 2)
            ax.errorbar(group["T"] + dodge, group[y], yerr=err, capsize=3, **style)
            hover.tag_rows(ax, group["T"] + dodge, group[y], group)
        else:
            ax.plot(group["T"], group[y], **style)
            hover.tag_rows(ax, group["T"], group[y], group)
        drawn += 1
    return drawn


def note_truncated(ax, total: int) -> None:
    ax.text(0.99, 0.01, f"showing {MAX_SERIES} of {total} series; all are in speedup.csv",
            transform=ax.transAxes, ha="right", va="bottom", fontsize=7, color="0.3")


def plot_speedup(table: pd.DataFrame, cores: int | None, stem: Path,
                 column: str = "speedup", title: str = "Speed-up",
                 ylabel: str = "speed-up (x)") -> Path | None:
    """Speed-up against T, one line per configuration, with the ideal line y = T."""
    table = table.dropna(subset=[column])
    if table.empty or table["T"].nunique() < 2:
        return None
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    ts = sorted(table["T"].unique())
    if column == "speedup":
        ax.plot(ts, ts, color="0.2", linestyle=":", linewidth=1.2, label="ideal (speed-up = T)")
    columns = series_columns(table)
    draw_series(ax, table, column, columns)
    mark_cores(ax, cores, max(ts))
    thread_axis(ax, ts)
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.set_title(f"{title} against threads\n{context(table, columns)}")
    outside_legend(ax)
    return save(fig, stem)


def plot_efficiency(table: pd.DataFrame, cores: int | None, stem: Path) -> Path | None:
    table = table.dropna(subset=["efficiency"])
    if table.empty or table["T"].nunique() < 2:
        return None
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    ts = sorted(table["T"].unique())
    ax.axhline(1.0, color="0.2", linestyle=":", linewidth=1.2, label="ideal (efficiency = 1)")
    columns = series_columns(table)
    draw_series(ax, table, "efficiency", columns)
    mark_cores(ax, cores, max(ts))
    thread_axis(ax, ts)
    ax.set_ylabel("parallel efficiency (speed-up / T)")
    ax.set_ylim(0, max(1.1, float(table["efficiency"].max()) * 1.1))
    ax.set_title(f"Efficiency against threads\n{context(table, columns)}")
    outside_legend(ax)
    return save(fig, stem)


def plot_wall_time(table: pd.DataFrame, cores: int | None, stem: Path) -> Path | None:
    """Minimum wall time against T; bars span min to max of the ok repetitions."""
    table = table.dropna(subset=["wall_s_min"])
    if table.empty or table["T"].nunique() < 2:
        return None
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    ts = sorted(table["T"].unique())
    columns = series_columns(table)
    unit, scale = time_unit(table["wall_s_max"])
    scaled = table.assign(wall_s_min=table["wall_s_min"] * scale,
                          wall_s_max=table["wall_s_max"] * scale)
    draw_series(ax, scaled, "wall_s_min", columns, "wall_s_min", "wall_s_max")
    mark_cores(ax, cores, max(ts))
    thread_axis(ax, ts)
    ax.set_ylabel(f"wall time ({unit}), min over repetitions")
    log_if_wide(ax, scaled["wall_s_min"], "y")
    ax.set_title(f"Wall time against threads (bars: min to max of repetitions)\n"
                 f"{context(table, columns)}")
    outside_legend(ax)
    return save(fig, stem)


def outside_legend(ax) -> None:
    """Legend right of the axes: with up to MAX_SERIES lines any inside spot hides data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)


def log_if_wide(ax, values, axis: str) -> None:
    """Log scale when values span more than a decade: otherwise the small ones are a flat line
    along the axis."""
    values = pd.Series(values).dropna()
    values = values[values > 0]
    if len(values) and values.max() / values.min() > 10:
        readable_log(ax, axis)


def plot_counter_vs_threads(tables: dict[str, pd.DataFrame], cores: int | None, stem: Path,
                            title: str, ylabel: str) -> Path | None:
    """One panel per counter (e.g. voluntary and involuntary context switches): median over
    repetitions, bars min to max. `tables` maps a panel title to an aggregate() frame."""
    tables = {name: t for name, t in tables.items() if not t.empty}
    if not tables:
        return None
    fig, axes = plt.subplots(1, len(tables), figsize=(5.5 * len(tables) + 1.5, 4.6), squeeze=False)
    for ax, (name, t) in zip(axes[0], tables.items()):
        column = [c for c in t.columns if c.endswith("_median")][0]
        base = column[: -len("_median")]
        columns = series_columns(t)
        draw_series(ax, t, column, columns, f"{base}_min", f"{base}_max")
        ts = sorted(t["T"].unique())
        mark_cores(ax, cores, max(ts))
        thread_axis(ax, ts)
        ax.set_ylabel(ylabel)
        if (t[f"{base}_min"] > 0).all():
            log_if_wide(ax, pd.concat([t[f"{base}_min"], t[f"{base}_max"]]), "y")
        ax.set_title(name)
    outside_legend(axes[0, -1])  # same series in every panel: one legend suffices
    first = next(iter(tables.values()))
    fig.suptitle(f"{title} (median, bars: min to max of repetitions)\n"
                 f"{context(first, series_columns(first))}")
    return save(fig, stem)


# ---------------------------------------------------------------- scaling (one-at-a-time)

def plot_scaling(table: pd.DataFrame, param: str, stem: Path) -> Path | None:
    """Wall time against one parameter on log-log axes, each series with its fitted power law;
    the exponent is in the legend (time ~ N^2 shows as a slope of 2)."""
    series = scaling_series(table, param)
    if len(series) > MAX_SERIES and param != "T" and (table["T"] == 1).any():
        # Too many lines to read (e.g. engines x thread counts): the sequential runs carry
        # the scaling law; the parallel ones are in the thread-count plots.
        series = scaling_series(table[table["T"] == 1], param) or series
    if not series:
        return None
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    if len(series) > MAX_SERIES:
        note_truncated(ax, len(series))
    all_rows = pd.concat([group for _, group in series])
    label_columns = [c for c in varying(all_rows, CONFIG_PARAMS + ["T"]) if c != param]
    fitted, against = False, []
    unit, scale = time_unit(all_rows["wall_s_max"])
    for i, (fixed, group) in enumerate(series[:MAX_SERIES]):
        color, marker = f"C{i % 10}", MARKERS[i % len(MARKERS)]
        label = series_label(fixed, label_columns) if label_columns else "measured"
        fit = fit_power_law(group[param], group["wall_s_min"])
        if fit:
            label += f": time ~ {SHORT.get(param, param)}^{fit.exponent:.2f}"
            xs = np.geomspace(group[param].min(), group[param].max(), 50)
            ax.plot(xs, scale * fit(xs), color=color, linestyle="--", linewidth=1)
            fitted = True
        err = [group["wall_s_min"] * 0, scale * (group["wall_s_max"] - group["wall_s_min"])]
        ax.errorbar(group[param], scale * group["wall_s_min"], yerr=err, capsize=3,
                    linestyle="none", marker=marker, color=color, label=label)
        hover.tag_rows(ax, group[param], scale * group["wall_s_min"], group)
        against += draw_unaffected(ax, table, param, fixed, group[param].min(), color, scale,
                                   [c for c in label_columns if c != "engine"], set(against))
    # At least a decade of y: a flat law (time ~ L^0) must look flat, not like noise magnified
    # to fill the axes.
    low, high = ax.get_ylim()
    if 0 < low and high / low < 10:
        middle = math.sqrt(low * high)
        ax.set_ylim(middle / math.sqrt(10), middle * math.sqrt(10))
    ax.set_ylabel(f"wall time ({unit}), min over repetitions")
    readable_log(ax, "y")
    ax.set_xscale("log")
    ax.set_xticks(sorted(all_rows[param].unique()))  # a tick at every measured value
    ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: fmt(v)))
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel(axis_label(param) + ", log scale")
    # Name the dashed lines only when some series had the three points a fit needs.
    note = " (dashed: fitted power law)" if fitted else " (too few points for a power-law fit)"
    if against:
        note += f"\nlevel lines: engines that do not use {SHORT.get(param, param)}, to compare with"
    ax.set_title(f"Wall time against {SHORT.get(param, param)}{note}\n"
                 f"{context(all_rows, label_columns + [param])}")
    outside_legend(ax)
    return save(fig, stem)


def draw_unaffected(ax, table: pd.DataFrame, param: str, fixed: dict, x, color, scale,
                    label_columns: list[str], drawn: set) -> list:
    """A level line per run of an engine that does not use `param` (brute beside grid's G) at
    the series `fixed`'s scene and T, in the series' colour, its point tagged at `x`: a time
    against `param` means little without the engines it competes with. Runs in `drawn` (shared
    by two series, grid's and grid-unsafe's) are drawn once; returns the indices drawn."""
    others = unaffected(table, param, fixed).drop(index=list(drawn), errors="ignore")
    where = series_label(fixed, label_columns) if label_columns else ""
    for k, (index, other) in enumerate(others.iterrows()):
        row = others.loc[[index]]
        ax.axhline(scale * other["wall_s_min"], color=color, linewidth=1.2,
                   linestyle=[":", "-."][k % 2],
                   label=f"{engine_name(row)}{', ' + where if where else ''} "
                         f"(does not use {SHORT.get(param, param)})")
        hover.tag_rows(ax, [x], [scale * other["wall_s_min"]], row)
    return list(others.index)


# ---------------------------------------------------------------- stage breakdown

def stage_label(column: str) -> str:
    """broad_phase_s -> "broad phase": a stage's name from its declared column."""
    return column.removesuffix("_s").replace("_", " ")


def plot_stage_times(records: pd.DataFrame, stem: Path, stage_columns: list[str]) -> Path | None:
    """Stacked horizontal bar per configuration: seconds in each pipeline stage (the declared
    stage-time columns, in pipeline order) of the fastest repetition, plus the rest of its wall
    time ("other": I/O-free loop overhead, barriers). One panel per N, because sizes that differ
    by decades would flatten each other."""
    stages = [c for c in stage_columns if c in records.columns and records[c].notna().any()]
    if records.empty or not stages:
        return None
    facet = "N" if records["N"].nunique() > 1 else None
    facets = list(records.groupby(facet, sort=True)) if facet else [(None, records)]
    facets = facets[:6]
    bar_columns = [c for c in varying(records, CONFIG_PARAMS + ["T"]) if c != facet]
    height = sum(max(1.6, 0.32 * len(f) + 0.9) for _, f in facets)
    fig, axes = plt.subplots(len(facets), 1, figsize=(8, min(height + 1, 30)), squeeze=False)
    colors = [f"C{i}" for i in range(len(stages))] + ["0.75"]
    for ax, (value, group) in zip(axes[:, 0], facets):
        unit, scale = time_unit(group["wall_s"])  # per panel: N=250 in ms, N=4000 in s
        group = group.sort_values(bar_columns or ["T"])
        labels = [series_label(row, bar_columns) for _, row in group.iterrows()]
        y = np.arange(len(group))
        left = np.zeros(len(group))
        parts = [(stage_label(c), scale * group[c].fillna(0).to_numpy()) for c in stages]
        other = np.clip(scale * group["wall_s"].to_numpy() - sum(p for _, p in parts), 0, None)
        parts.append(("other (wall - stages)", other))
        for (name, seconds), color in zip(parts, colors):
            ax.barh(y, seconds, left=left, color=color, label=name, height=0.7)
            left += seconds
        hover.tag_rows(ax, left, y, group, value="x")  # the bar's end: the whole wall time
        ax.set_yticks(y)
        ax.set_yticklabels(labels)
        ax.invert_yaxis()
        ax.set_xlabel(f"time ({unit}) of the fastest repetition")
        ax.set_title(f"N={fmt(value)}" if facet else context(records, bar_columns))
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.suptitle(f"Time per pipeline stage\n{context(records, bar_columns + [facet or ''])}")
    legend_room = 0.55 / fig.get_figheight()  # about half an inch, whatever the figure height
    fig.tight_layout(rect=(0, legend_room, 1, 1))  # the legend goes below, outside the bars
    fig.legend(handles, labels, loc="lower center", ncol=4, frameon=False)
    return save(fig, stem, layout=False)
