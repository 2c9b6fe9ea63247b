"""Drawing for runs on ranks (ranks.py): speed-up and the communication share of the loop against
the cores a run takes (P x T), a line per T so that P is what moves along a line, and weak
scaling over P. Same contract as figures.py: tables in, files out, None when there is nothing
to draw.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from analysis.common import hover
from analysis.common.figures import MARKERS, plt, save
from analysis.common.labels import fmt
from analysis.plots.figures import context, mark_cores, outside_legend


def _lines(ax, rows: pd.DataFrame, y: str, linestyle: str = "-", suffix: str = "") -> None:
    """One line per (N, T) against P x T, labelled with its P values' range."""
    for i, ((n, t), line) in enumerate(rows.groupby(["N", "T"], sort=True)):
        line = line.sort_values("workers").dropna(subset=[y])
        if line.empty:
            continue
        ax.plot(line["workers"], line[y], marker=MARKERS[i % len(MARKERS)], color=f"C{i % 10}",
                linestyle=linestyle,
                label=f"N={fmt(n)}, T={fmt(t)}, P={fmt(line['P'].min())}..{fmt(line['P'].max())}"
                      + suffix)
        hover.tag_rows(ax, line["workers"], line[y], line)


def _worker_axis(ax, workers, cores) -> None:
    ticks = sorted(set(int(w) for w in workers))
    mark_cores(ax, cores, max(ticks))
    ax.set_xticks(ticks)
    ax.set_xlim(0.5, max(ticks) + 0.5)
    ax.set_xlabel("cores taken P × T (ranks × threads)")


def plot_ranks(ranks: pd.DataFrame, weak: pd.DataFrame, cores: int | None,
               stem: Path) -> Path | None:
    """Speed-up over P = 1, T = 1 against P x T (ideal: the diagonal); the slowest rank's
    share of the loop in MPI (solid) and waiting (dashed); weak-scaling efficiency against P
    where the sweep has a weak series. Needs two P values: one shows no scaling."""
    if ranks.empty or ranks["P"].nunique() < 2:
        return None
    panels = 3 if not weak.empty else 2
    fig, axes = plt.subplots(1, panels, figsize=(6.2 * panels, 4.6))
    speed, share = axes[0], axes[1]
    strong = ranks.dropna(subset=["speedup_P"])
    workers = sorted(ranks["workers"].unique())
    speed.plot(workers, workers, color="0.2", linestyle=":", linewidth=1.2, label="ideal")
    _lines(speed, strong, "speedup_P")
    speed.set_ylabel("speed-up t(P=1, T=1) / t(P, T)")
    speed.set_title("Strong scaling over ranks and threads")
    _lines(share, ranks, "comm_share", suffix=": in MPI")
    _lines(share, ranks, "wait_share", linestyle="--", suffix=": waiting")
    share.set_ylabel("share of the loop (slowest rank)")
    share.set_title("Communication share of the loop")
    for ax in (speed, share):
        _worker_axis(ax, workers, cores)
        ax.set_ylim(bottom=0)
    outside_legend(share)
    if not weak.empty:
        ax = axes[2]
        ax.axhline(1.0, color="0.2", linestyle=":", linewidth=1.2, label="ideal")
        for i, (t, series) in enumerate(weak.groupby("T", sort=True)):
            series = series.sort_values("P")
            ax.plot(series["P"], series["weak_efficiency_P"], marker=MARKERS[i % len(MARKERS)],
                    color=f"C{i % 10}", label=f"T={fmt(t)}: N {fmt(series['N'].iloc[0])} to "
                                              f"{fmt(series['N'].iloc[-1])}")
            hover.tag_rows(ax, series["P"], series["weak_efficiency_P"], series)
        ps = sorted(set(int(p) for p in weak["P"]))
        ax.set_xticks(ps)
        ax.set_xlabel("ranks P")
        ax.set_ylabel("weak-scaling efficiency t(P=1) / t(P)")
        ax.set_title("Weak scaling: N grows with P")
        ax.set_ylim(bottom=0)
        outside_legend(ax)
    fig.suptitle(f"Ranks: one simulation on P processes\n"
                 f"{context(ranks, ['N', 'L', 'P', 'T'])}")
    return save(fig, stem)
