"""report.md: a sweep explained on one page, readable without the CSVs.

Sections: provenance (what a reader needs of meta.json), run accounting (failed runs are
counted, never hidden), the scoreboard of a sweep with external programs, optimal thread count
and peak speed-up per configuration, each engine against the machine's ceilings, power-law fits,
state-hash agreement, then every plot embedded with a path relative to the report so the folder
can be moved whole.
"""
from __future__ import annotations

import shlex
from pathlib import Path

import pandas as pd

from analysis.plots.fits import MIN_POINTS
from analysis.common.labels import SHORT, fmt
from analysis.common.load import CONFIG_PARAMS, SCENE_PARAMS, Results, status_counts
from analysis.common.markdown import markdown_table
from analysis.common.page import write_pages
from analysis.plots.cost import auto_versus_fastest
from analysis.plots.ceilings import Ceilings
from analysis.plots.ranks import ranks_table, weak_ranks_table
from analysis.plots.sections import (ceilings_section, cost_section, measurement_section,
                                     ranks_section,
                                     serial_section, weak_section)
from analysis.plots.weak import weak_table
from analysis.scoreboard.board import scoreboard, scoreboard_markdown
from analysis.common.stats import varying
from analysis.plots.tables import cpu_share, failure_table, hash_agreement, peak_table

# Below this share of a core at T=1 the machine was visibly busy during the sweep.
BUSY_THRESHOLD = 0.9

def provenance(results: Results) -> str:
    """What a reader needs to trust or reproduce the numbers: when, which commit, which machine,
    which compiler and flags, which counters could be read, the command, and the engines and
    metrics the sweep used. The rest (the sweep's config, psim's whole declaration, paths) stays
    in meta.json."""
    meta = results.meta
    if not meta:
        return "_meta.json is missing: provenance unknown._\n"
    git, build = section(meta, "git"), section(meta, "build")
    machine, counters = section(meta, "machine"), section(meta, "counters")
    commit = f"`{git['commit']}`" if git.get("commit") else "unknown"
    if git.get("dirty"):
        commit += " with uncommitted changes"
    host = ", ".join(str(machine[k]) for k in ("hostname", "cpu_model") if machine.get(k))
    cpus = ", ".join(f"{machine[k]} {unit}" for k, unit in
                     (("online_cpus", "CPUs"), ("physical_cores", "cores")) if machine.get(k))
    system = ", ".join(str(machine[k]) for k in ("kernel", "arch") if machine.get(k))
    compiler = " ".join(filter(None, [build.get("compiler"),
                                      f"`{build['flags']}`" if build.get("flags") else None,
                                      f"({build['build_type']})" if build.get("build_type")
                                      else None]))
    openmp = " ".join(str(v) for v in (section(meta, "openmp").get(k) for k in
                                       ("runtime", "version")) if v)
    if openmp:
        compiler += f"; OpenMP {openmp}"
    readable = [kind for kind in ("software", "hardware") if counters.get(kind)]
    counted = (", ".join(readable) or "none") + (f" ({counters['note']})"
                                                 if counters.get("note") else "")
    items = [("date", meta.get("date")), ("commit", commit),
             ("machine", "; ".join(filter(None, [host, cpus, system]))),
             ("compiler", compiler), ("counters", counted if counters else None),
             ("command", f"`{command_text(meta['command_line'])}`" if meta.get("command_line")
              else None)]
    lines = [f"- {name}: {value}" for name, value in items if value]
    return ("\n".join(lines) + "\n\n" + used_engines(results) + used_metrics(results)
            + "The sweep's configuration and psim's whole declaration are in `meta.json`.\n")


def command_text(command) -> str:
    """psweep records its argv as a list: shown as a shell line a reader can paste."""
    return shlex.join(map(str, command)) if isinstance(command, list) else str(command)


def section(meta: dict, key: str) -> dict:
    value = meta.get(key)
    return value if isinstance(value, dict) else {}


def used_engines(results: Results) -> str:
    """The declared engines this sweep ran, one row each."""
    names = set(results.runs["engine"].dropna())
    engines = [e for e in results.declaration.engines if e.get("name") in names]
    if not engines:
        return ""
    table = pd.DataFrame({"engine": [e["name"] for e in engines],
                          "exact": [yes(e.get("exact")) for e in engines],
                          "matches reference": [yes(e.get("matches_reference")) for e in engines],
                          "reads": [", ".join(SHORT.get(u, u) for u in e.get("uses", []))
                                    for e in engines],
                          "about": [e.get("about", "") for e in engines]})
    return "### Engines the sweep ran\n\n" + markdown_table(table) + "\n"


def used_metrics(results: Results) -> str:
    """The declared metrics with a value in at least one of this sweep's runs, one row each."""
    runs = results.runs
    metrics = [m for m in results.declaration.metrics
               if m.get("key") in runs.columns and runs[m["key"]].notna().any()]
    if not metrics:
        return ""
    table = pd.DataFrame({"metric": [m["key"] for m in metrics],
                          "kind": [m.get("kind", "") for m in metrics],
                          "unit": [m.get("unit", "") for m in metrics],
                          "about": [m.get("about", "") for m in metrics]})
    return "### Metrics psim reported\n\n" + markdown_table(table) + "\n"


def yes(flag) -> str:
    return "yes" if flag else ""


def accounting(results: Results, failed_listing: int = 20) -> str:
    counts = status_counts(results.runs)
    total = sum(counts.values())
    ok = counts.get("ok", 0)
    text = f"{total} recorded runs: {ok} ok"
    bad = {k: v for k, v in counts.items() if k != "ok"}
    if bad:
        text += ", " + ", ".join(f"{v} {k}" for k, v in bad.items())
        text += (". Runs that did not succeed are left out of every minimum, speed-up and "
                 "plot.\n\n")
        failed = failure_table(results.runs)
        shown = failed[[c for c in failed.columns
                        if c in varying(failed, CONFIG_PARAMS) + ["T", "rep", "status",
                                                                  "exit_code", "error"]]]
        text += markdown_table(shown.head(failed_listing))
        if len(failed) > failed_listing:
            text += f"\n… and {len(failed) - failed_listing} more (see runs.csv).\n"
    else:
        text += ", none failed.\n"
    over = results.ok[results.ok["oversubscribed"] == 1]
    if len(over):
        text += (f"\n{len(over)} ok runs used more threads than the machine has cores "
                 f"(oversubscribed): expect their times to be noisy.\n")
    return text


def peak_section(speedup: pd.DataFrame) -> str:
    if speedup["T"].nunique() < 2:
        return "This sweep ran a single thread count, so there is no speed-up to tabulate.\n"
    peaks = peak_table(speedup)
    if peaks.empty:
        return "No configuration has both a T=1 run and another thread count.\n"
    text = ("`optimal T` is the thread count with the lowest minimum wall time, `peak` its "
            "speed-up over T=1 of the same configuration, `efficiency` = peak / T.\n")
    for engine, group in peaks.groupby("engine", sort=True):
        keys = [c for c in varying(group, CONFIG_PARAMS) if c != "engine"]
        by = " and ".join(SHORT.get(k, k) for k in keys) or "configuration"
        shown = group[keys + ["optimal_T", "peak_speedup", "efficiency", "wall_s_T1",
                              "wall_s_best"]].rename(columns={
                                  "optimal_T": "optimal T", "peak_speedup": "peak speed-up",
                                  "wall_s_T1": "wall s at T=1",
                                  "wall_s_best": "wall s at optimal T"})
        text += f"\n### {engine}: optimal T and peak speed-up per {by}\n\n"
        text += f"{context_line(group, keys)}\n\n" + markdown_table(shown)
    return text


def context_line(frame: pd.DataFrame, exclude) -> str:
    fixed = [c for c in ["N", "L", "r", "S", "slow_factor", "G", "pin"]
             if c not in exclude and frame[c].nunique(dropna=True) == 1]
    if not fixed:
        return ""
    return "Fixed: " + ", ".join(f"{SHORT.get(c, c)}={fmt(frame[c].dropna().iloc[0])}"
                                 for c in fixed) + "."


def fits_section(fits: pd.DataFrame) -> str:
    """Only series with an exponent go into the table (a product sweep's two-point series would
    fill it with empty rows); the others are counted, with the reason they have none."""
    if fits.empty:
        return ""
    intro = ("\n## Scaling\n\nWall time fitted as a power law t = a·x^b in each varied "
             "parameter (log-log least squares): b ≈ 2 in N is quadratic, b ≈ 0 is flat.\n\n")
    fitted = fits.dropna(subset=["exponent"])
    unfitted = fits[fits["exponent"].isna()]
    why = ""
    if len(unfitted):
        params = ", ".join(sorted({SHORT.get(p, p) for p in unfitted["parameter"]}))
        most = int(unfitted["points"].max())
        reason = (f"at most {most} distinct values, and a fit needs {MIN_POINTS} (any "
                  f"exponent goes exactly through two points, so it would claim nothing); "
                  f"sweep more values to get one.\n")
        if fitted.empty:
            why = f"No power-law fit: every series against {params} has {reason}"
        else:
            why = f"{len(unfitted)} more series against {params} get no exponent: {reason}"
    if fitted.empty:
        return intro + why
    keys = varying(fitted, CONFIG_PARAMS + ["T"])
    held = fitted.apply(lambda row: ", ".join(
        f"{SHORT.get(k, k)}={fmt(row[k])}" for k in keys if k != row["parameter"]), axis=1)
    shown = pd.DataFrame({"parameter": fitted["parameter"].map(lambda p: SHORT.get(p, p)),
                          "held fixed": held if keys else "",
                          "range": fitted["low"].map(fmt) + " to " + fitted["high"].map(fmt),
                          "points": fitted["points"],
                          "exponent b": fitted["exponent"].round(2),
                          "R²": fitted["r_squared"].round(3)})
    if not keys:
        shown = shown.drop(columns="held fixed")
    return intro + markdown_table(shown) + ("\n" + why if why else "")


def hash_section(results: Results) -> str:
    table = hash_agreement(results.runs, results.declaration.exact_engines)
    if table.empty:
        return ""
    disagree = table[table["distinct_hashes"] > 1]
    text = "\n## Determinism\n\n"
    if disagree.empty:
        return text + (f"All {int(table['runs'].sum())} ok runs of the exact engines agree "
                       f"on the final state hash of their scene ({len(table)} scene(s)), "
                       f"whatever the engine and thread count.\n")
    keys = varying(table, SCENE_PARAMS)
    return text + ("**Final state hashes disagree** for these scenes (docs/model.md "
                   "promises bit-identical results across engines and thread counts):\n\n"
                   + markdown_table(disagree[keys + ["runs", "distinct_hashes"]]))


def load_section(results: Results) -> str:
    table = cpu_share(results.runs, results.cores)
    if table.empty:
        return ""
    text = ("\n## Machine load\n\n`cpu share` = (user + sys CPU time) / (process wall time × "
            "min(P × T, cores)), median over the ok runs (P: a run's ranks, 1 without): 1 means "
            "the run had its cores to itself. A run of ranks counts its launcher's start, which "
            "mostly waits (mpirun: about 0.3 s), so its share is low on a short run and says "
            "nothing of the machine.\n\n")
    # The machine's load is read off single-thread runs of one process: a launcher's start is
    # mostly waiting, not other work.
    one = table["T"] == 1
    if "P" in table.columns:
        one &= table["P"].isna()
    sequential = table[one]
    busy = sequential[sequential["cpu_share"] < BUSY_THRESHOLD]
    if len(busy):
        worst = busy["cpu_share"].min()
        text += (f"**Warning: the machine was busy.** Single-thread runs got a median of only "
                 f"{worst:.0%} of a core, so other processes competed for the CPUs. Speed-ups "
                 f"measured this way are unreliable, and often inflated: a process with more "
                 f"threads wins a larger share of a contended CPU. Re-run on a quiet "
                 f"machine before drawing conclusions.\n\n")
    shown = table.rename(columns={"cpu_share": "cpu share"})
    return text + markdown_table(shown)


def scoreboard_section(results: Results) -> str:
    """The external programs beside the engines, judged and timed (docs/programs.md); nothing
    for a sweep of engines only."""
    if not results.programs:
        return ""
    board = scoreboard(results.runs, results.programs, results.declaration)
    return ("\n## Scoreboard\n\nThe external programs and the engines per scene, sorted by "
            "`psim check`'s verdict, then by the best whole-process time "
            "(`/usr/bin/python3 -m analysis scoreboard`, docs/programs.md).\n\n"
            + scoreboard_markdown(board))


def write_report(path: Path, results: Results, speedup: pd.DataFrame, fits: pd.DataFrame,
                 figures: list[tuple[str, Path]]) -> None:
    name = (results.meta.get("config") or {}).get("name") or results.directory.name
    ranks = ranks_table(speedup, results.runs, results.declaration)
    parts = [f"# Sweep report: {name}\n",
             f"Generated by `/usr/bin/python3 -m analysis plots` from `{results.directory}`. Times are the "
             "minimum over successful repetitions (noise only ever adds time); full numbers "
             "in `speedup.csv` and `runs.csv`.\n",
             "## Provenance\n", provenance(results),
             "\n## Runs\n", accounting(results),
             scoreboard_section(results),
             measurement_section(results, speedup),
             "\n## Speed-up\n", peak_section(speedup),
             serial_section(speedup, results.cores),
             weak_section(weak_table(speedup, results.cores)),
             ranks_section(ranks, weak_ranks_table(ranks)),
             cost_section(auto_versus_fastest(speedup, results.declaration.exact_engines)),
             ceilings_section(speedup, Ceilings.from_meta(results.meta)),
             load_section(results),
             fits_section(fits),
             hash_section(results)]
    if figures:
        parts.append("\n## Plots\n")
        for title, png in figures:
            rel = png.relative_to(path.parent).as_posix()
            svg = png.with_suffix(".svg").relative_to(path.parent).as_posix()
            parts.append(f"\n### {title}\n\n![{title}]({rel})\n\n([SVG]({svg}))\n")
    write_pages(path, "\n".join(parts))
