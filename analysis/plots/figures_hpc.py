"""Drawing for the parallel-performance views: the Karp-Flatt serial fraction, weak scaling
and cost per unit of work. Same contract as figures.py (tables in, files out, None when there is
nothing to draw) and the same helpers, so these plots read like the rest.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd

from analysis.common import hover
from analysis.common.figures import MARKERS, engine_styles, plt, save
from analysis.common.labels import fmt, series_label
from analysis.common.load import CONFIG_PARAMS
from analysis.common.stats import varying
from analysis.plots.cost import CONTEST_KEYS, unjudged_picks
from analysis.plots.counters import COUNTERS
from analysis.plots.figures import (MAX_SERIES, context, draw_series, log_if_wide, mark_cores,
                                    outside_legend, series_columns, thread_axis)
from analysis.plots.weak import SERIES_KEYS

def plot_karp_flatt(table: pd.DataFrame, cores: int | None, stem: Path) -> Path | None:
    """Karp-Flatt e against T (T > 1), one line per configuration, with each configuration's
    Amdahl f as a dashed level of the same colour: where e leaves it, Amdahl's law stops
    describing the code. Needs two thread counts above 1: a single point shows no trend."""
    rated = table.dropna(subset=["karp_flatt"])
    if rated["T"].nunique() < 2:
        return None
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    columns = series_columns(rated)
    draw_series(ax, rated, "karp_flatt", columns)
    by = columns[0] if len(columns) == 1 else columns
    groups = list(rated.groupby(by, dropna=False, sort=True)) if columns else [((), rated)]
    ts = sorted(rated["T"].unique())
    dashed = False
    for i, (_, group) in enumerate(groups[:MAX_SERIES]):
        f = group["amdahl_f"].iloc[0]
        if np.isfinite(f):
            ax.hlines(f, ts[0], ts[-1], colors=f"C{i % 10}", linestyles="--", linewidth=1)
            dashed = True
    mark_cores(ax, cores, max(ts))
    thread_axis(ax, ts)
    ax.axhline(0, color="0.2", linewidth=0.8)
    ax.set_ylabel("Karp-Flatt serial fraction e")
    fitted_on = f" on T <= {cores}" if cores else ""
    fit_note = f"; dashed: Amdahl f fitted{fitted_on}" if dashed else ""
    ax.set_title(f"Serial fraction against threads (rising: overhead grows with T"
                 f"{fit_note})\n{context(rated, columns)}")
    outside_legend(ax)
    return save(fig, stem)


def plot_cost_per_step(table: pd.DataFrame, contests: pd.DataFrame, stem: Path) -> Path | None:
    """ns per particle-step against N, one line per engine (and G), one panel per T: the lowest
    line at an N is the engine to use there. An engine that picks (auto) is drawn as open black
    circles at its own cost; a red cross marks each N where its choice was not the fastest
    measured engine, labelled with its choice."""
    rated = table.dropna(subset=["ns_per_particle_step"])
    if rated.empty or rated["N"].nunique() < 2:
        return None
    pickers = set(contests["picker"].dropna()) if len(contests) else set()
    ts = sorted(rated["T"].unique())[:4]
    fig, axes = plt.subplots(1, len(ts), figsize=(4.8 * len(ts) + 2.2, 4.6), squeeze=False,
                             sharey=True)
    lines = rated[~rated["engine"].isin(pickers)]
    columns = [c for c in varying(lines, CONFIG_PARAMS) if c != "N"] or ["engine"]
    missed_any = False
    line_style = engine_styles(lines)
    for ax, t in zip(axes[0], ts):
        at_t = lines[lines["T"] == t]
        by = columns[0] if len(columns) == 1 else columns
        for i, (_, group) in enumerate(list(at_t.groupby(by, dropna=False, sort=True))
                                       [:MAX_SERIES]):
            group = group.sort_values("N")
            ax.plot(group["N"], group["ns_per_particle_step"], marker=MARKERS[i % len(MARKERS)],
                    color=f"C{i % 10}", label=series_label(group.iloc[0], columns),
                    linestyle=line_style.get(group["engine"].iloc[0], "-"))
            hover.tag_rows(ax, group["N"], group["ns_per_particle_step"], group)
        for picker in sorted(pickers):
            own = rated[(rated["engine"] == picker) & (rated["T"] == t)].sort_values("N")
            ax.plot(own["N"], own["ns_per_particle_step"], "o", markerfacecolor="none",
                    markeredgecolor="black", markersize=9, label=f"{picker} (its own runs)")
            hover.tag_rows(ax, own["N"], own["ns_per_particle_step"], own)
            missed = contests[(contests["picker"] == picker) & (contests["T"] == t)
                              & (contests["picked_is_fastest"] == False)]  # noqa: E712
            missed = missed.merge(own[CONTEST_KEYS + ["ns_per_particle_step"]], on=CONTEST_KEYS)
            if len(missed):
                missed_any = True
                ax.plot(missed["N"], missed["ns_per_particle_step"], "x", color="C3",
                        markersize=11, markeredgewidth=2,
                        label=f"{picker} picked another engine than the fastest")
                for _, row in missed.iterrows():
                    ax.annotate(f"picked {row['picked']}, fastest {row['fastest']}",
                                (row["N"], row["ns_per_particle_step"]), fontsize=7,
                                color="C3", xytext=(4, 6), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_xticks(sorted(rated["N"].unique()))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: fmt(v)))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("N (particles), log scale")
        ax.set_title(f"T={fmt(t)}")
    axes[0, 0].set_ylabel("ns per particle-step (wall time / (N S K))")
    log_if_wide(axes[0, 0], rated["ns_per_particle_step"], "y")
    handles, labels = axes[0, -1].get_legend_handles_labels()
    unique = dict(zip(labels, handles))
    axes[0, -1].legend(unique.values(), unique.keys(), loc="upper left",
                       bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    marks = "; red x: the pick was not the fastest" if missed_any else ""
    unjudged = unjudged_picks(contests) if len(contests) else []
    if unjudged:  # no cross cannot mean a good pick when the picked engine was never timed
        marks += f"; picks of {', '.join(unjudged)} not judged: not swept on their own"
    fig.suptitle(f"Cost per particle-step against N (lowest line wins{marks})\n"
                 f"{context(rated, columns + ['N', 'T', 'engine'])}")
    return save(fig, stem)


def plot_weak_scaling(weak: pd.DataFrame, cores: int | None, stem: Path) -> Path | None:
    """Two panels against T: weak-scaling efficiency t(1)/t(T) (ideal 1) and Gustafson's scaled
    speed-up (ideal T) with each series' fitted Gustafson law dashed. One line per series,
    labelled with the N it grows through."""
    if weak.empty:
        return None
    columns = varying(weak, SERIES_KEYS) or ["engine"]
    by = columns[0] if len(columns) == 1 else columns
    groups = list(weak.groupby(by, dropna=False, sort=True))[:MAX_SERIES]
    ts = sorted(weak["T"].unique())
    fig, (left, right) = plt.subplots(1, 2, figsize=(12.5, 4.6))
    left.axhline(1.0, color="0.2", linestyle=":", linewidth=1.2, label="ideal")
    right.plot(ts, ts, color="0.2", linestyle=":", linewidth=1.2, label="ideal")
    dashed = False
    for i, (_, series) in enumerate(groups):
        series = series.sort_values("T")
        label = (f"{series_label(series.iloc[0], columns)}: "
                 f"N {fmt(series['N'].iloc[0])} to {fmt(series['N'].iloc[-1])}")
        style = dict(marker=MARKERS[i % len(MARKERS)], color=f"C{i % 10}", label=label)
        left.plot(series["T"], series["weak_efficiency"], **style)
        right.plot(series["T"], series["scaled_speedup"], **style)
        hover.tag_rows(left, series["T"], series["weak_efficiency"], series)
        hover.tag_rows(right, series["T"], series["scaled_speedup"], series)
        s = series["gustafson_serial"].iloc[0]
        if np.isfinite(s):
            xs = np.array(ts, dtype=float)
            right.plot(xs, xs - s * (xs - 1), color=f"C{i % 10}", linestyle="--", linewidth=1,
                       label=f"Gustafson fit, serial fraction {s:.2f}")
            dashed = True
    for ax in (left, right):
        mark_cores(ax, cores, max(ts))
        thread_axis(ax, ts)
        ax.set_ylim(bottom=0)
    left.set_ylabel("weak-scaling efficiency t(1) / t(T)")
    left.set_title("Efficiency (ideal 1: T times the work in the same time)")
    right.set_ylabel("scaled speed-up T · t(1) / t(T)")
    right.set_title("Gustafson's scaled speed-up" + (" (dashed: fitted law)" if dashed else ""))
    outside_legend(right)
    fig.suptitle(f"Weak scaling: N grows with T\n{context(weak, columns + ['N', 'L', 'T'])}")
    return save(fig, stem)


def plot_ceilings(table: pd.DataFrame, stem: Path) -> Path | None:
    """Each engine's share of this machine's ceilings against N (ceilings.py), one panel per T:
    solid the pair kernel's peak, dashed memory bandwidth; 100% is the ceiling itself. Nothing
    without the ceilings (an older sweep) or with a single N."""
    rated = table.dropna(subset=["pair_peak_pct", "bandwidth_pct"], how="all")
    if rated.empty or rated["N"].nunique() < 2:
        return None
    ts = sorted(rated["T"].unique())[:4]
    fig, axes = plt.subplots(1, len(ts), figsize=(4.8 * len(ts) + 2.2, 4.6), squeeze=False,
                             sharey=True)
    engines = sorted(rated["engine"].unique())[:MAX_SERIES]
    for ax, t in zip(axes[0], ts):
        for i, engine in enumerate(engines):
            rows = rated[(rated["engine"] == engine) & (rated["T"] == t)].sort_values("N")
            style = dict(marker=MARKERS[i % len(MARKERS)], color=f"C{i % 10}")
            ax.plot(rows["N"], rows["pair_peak_pct"], label=f"{engine}: % of pair peak", **style)
            ax.plot(rows["N"], rows["bandwidth_pct"], linestyle="--",
                    label=f"{engine}: % of bandwidth", **style)
            hover.tag_rows(ax, rows["N"], rows["pair_peak_pct"], rows)
        ax.axhline(100, color="0.2", linestyle=":", linewidth=1.2, label="the ceiling")
        ax.set_xscale("log")
        ax.set_xticks(sorted(rated["N"].unique()))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: fmt(v)))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("N (particles), log scale")
        ax.set_ylim(bottom=0)
        ax.set_title(f"T={fmt(t)}")
    axes[0, 0].set_ylabel("% of this machine's ceiling")
    outside_legend(axes[0, -1])
    fig.suptitle("Against this machine's ceilings (meta.json `ceilings`)\n"
                 f"{context(rated, ['N', 'T', 'engine'])}")
    return save(fig, stem)


def plot_counters_per_step(counts: pd.DataFrame, marks: list[tuple[str, float]],
                           stem: Path) -> Path | None:
    """counters.py's counters per particle-step against N, a panel per counter and a line per
    engine at its smallest T, the caches' N marked; nothing with fewer than two N counted."""
    if counts.empty or counts["N"].nunique() < 2:
        return None
    present = [(c, name) for c, name in COUNTERS if c in counts and counts[c].notna().any()]
    fig, axes = plt.subplots(1, len(present), figsize=(4.6 * len(present) + 2.2, 4.4),
                             squeeze=False)
    engines = sorted(counts["engine"].unique())[:MAX_SERIES]
    for ax, (column, name) in zip(axes[0], present):
        for i, engine in enumerate(engines):
            mine = counts[counts["engine"] == engine]
            rows = mine[mine["T"] == mine["T"].min()].sort_values("N")
            ax.plot(rows["N"], rows[column], marker=MARKERS[i % len(MARKERS)], color=f"C{i % 10}",
                    label=f"{engine} ({', '.join(sorted(set(rows['source'])))})")
            hover.tag_rows(ax, rows["N"], rows[column], rows)
        low, high = counts["N"].min(), counts["N"].max()
        for label, n in marks:
            if low <= n <= high:
                ax.axvline(n, color="0.5", linestyle=":", linewidth=1)
                ax.annotate(label, (n, 1), xycoords=("data", "axes fraction"), va="top",
                            ha="right", rotation=90, color="0.35", fontsize=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("N (particles), log scale")
        ax.set_title(f"{name} per particle-step")
    outside_legend(axes[0, -1])
    fig.suptitle("Counters per particle-step (runs.csv counters_source: hardware or simulated)"
                 f"\n{context(counts, ['N', 'T', 'engine'])}")
    return save(fig, stem)
