"""Which plots a sweep gets: the plan from tables to figure files, in report order.

Thread-count plots are drawn per engine (engines differ by orders of magnitude, one axis would
hide the slow or the fast ones). A grid sweep over both N and G gets one speed-up plot per N
with a line per G: the 2019 report's "speed-up per G" view. Plots whose data are absent (one
thread count only, no stage timings, counters empty on a VM) are skipped, not drawn empty.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from analysis.common.labels import SHORT, engine_name, fmt
from analysis.common.load import Results
from analysis.common.stats import aggregate, record_runs
from analysis.plots import figures, figures_hpc, figures_ranks
from analysis.plots.cost import auto_versus_fastest
from analysis.plots.counters import cache_marks, counters_per_step
from analysis.plots.fits import scaling_params
from analysis.plots.ranks import ranks_table, weak_ranks_table
from analysis.plots.weak import weak_table

# rusage splits switches by cause (a thread waiting at a barrier vs one preempted because
# threads outnumber free cores), which is what explains a speed-up curve; perf's total is the
# fallback when rusage columns are empty.
SWITCH_COUNTERS = [("voluntary_switches", "voluntary (thread waited: barriers, I/O)"),
                   ("involuntary_switches", "involuntary (thread preempted)")]
PERF_SWITCHES = ("context_switches", "all (perf software counter)")


def draw_all(results: Results, table: pd.DataFrame, out: Path) -> list[tuple[str, Path]]:
    drawn: list[tuple[str, Path]] = []

    def add(title, path):
        if path is not None:
            drawn.append((title, path))

    cores = results.cores
    for engine, rows in table.groupby("engine", sort=True):
        if rows["T"].nunique() < 2:
            continue
        name = engine_name(rows)  # auto's plots say which engine's time they show
        # G is empty for engines that ignore it, so only an engine that uses G varies it.
        if rows["G"].nunique() > 1 and rows["N"].nunique() > 1:
            for n, per_n in rows.groupby("N", sort=True):
                add(f"{name}: speed-up per G at N={fmt(n)}",
                    figures.plot_speedup(per_n, cores,
                                         out / f"speedup_{engine}_N{fmt(n)}"))
        else:
            add(f"{name}: speed-up against threads",
                figures.plot_speedup(rows, cores, out / f"speedup_{engine}"))
        add(f"{name}: wall time against threads",
            figures.plot_wall_time(rows, cores, out / f"wall_time_{engine}"))
        add(f"{name}: parallel efficiency",
            figures.plot_efficiency(rows, cores, out / f"efficiency_{engine}"))
        add(f"{name}: serial fraction (Karp-Flatt) against threads",
            figures_hpc.plot_karp_flatt(rows, cores, out / f"karp_flatt_{engine}"))
        runs = results.runs[results.runs["engine"] == engine]
        panels = {name: aggregate(runs, column) for column, name in SWITCH_COUNTERS}
        if all(p.empty for p in panels.values()):
            column, name = PERF_SWITCHES
            panels = {name: aggregate(runs, column)}
        add(f"{name}: context switches against threads",
            figures.plot_counter_vs_threads(panels, cores, out / f"context_switches_{engine}",
                                            "Context switches per run", "context switches"))

    reference = results.declaration.reference
    others = table[(table["engine"] != reference) & table["speedup_vs_brute"].notna()]
    if not others.empty:
        # A line per engine (and per varied parameter) against the sequential reference.
        vs_brute = table[table["speedup_vs_brute"].notna()]
        add(f"speed-up over sequential {reference}",
            figures.plot_speedup(vs_brute, cores, out / "speedup_vs_brute",
                                 column="speedup_vs_brute",
                                 title=f"Speed-up over {reference} at T=1",
                                 ylabel=f"speed-up over {reference} T=1 (x)"))

    add("weak scaling: efficiency and Gustafson's scaled speed-up",
        figures_hpc.plot_weak_scaling(weak_table(table, cores), cores, out / "weak_scaling"))
    ranks = ranks_table(table, results.runs, results.declaration)
    add("ranks: speed-up and communication share against P x T, weak scaling over P",
        figures_ranks.plot_ranks(ranks, weak_ranks_table(ranks), cores, out / "ranks"))
    contests = auto_versus_fastest(table, results.declaration.exact_engines)
    add("cost per particle-step against N, per engine",
        figures_hpc.plot_cost_per_step(table, contests, out / "cost_per_particle_step"))
    add("each engine against this machine's ceilings",
        figures_hpc.plot_ceilings(table, out / "ceilings"))
    add("counters per particle-step against N, the caches marked",
        figures_hpc.plot_counters_per_step(counters_per_step(results.runs),
                                           cache_marks(results.meta), out / "counters_per_step"))

    for param in scaling_params(table):
        add(f"wall time against {SHORT.get(param, param)}",
            figures.plot_scaling(table, param, out / f"scaling_{param}"))

    records = record_runs(results.runs)
    for engine, rows in records.groupby("engine", sort=True):
        add(f"{engine_name(rows)}: time per pipeline stage",
            figures.plot_stage_times(rows, out / f"stage_times_{engine}",
                                     results.declaration.stage_columns))
    return drawn
