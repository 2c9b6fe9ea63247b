"""report.md sections for the parallel-performance views (serial fraction, weak scaling, cost per
unit of work, the machine's ceilings) and the warnings about how well the sweep could measure at
all. Each takes computed tables and returns markdown ('' when the sweep has nothing for it), like
those in report.py.
"""
from __future__ import annotations

import pandas as pd

from analysis.common import advice
from analysis.common.labels import SHORT, fmt
from analysis.common.load import CONFIG_PARAMS, Results
from analysis.common.markdown import markdown_table
from analysis.common.stats import varying
from analysis.plots.ceilings import (CEILING_COLUMNS, STATE_BYTES, Ceilings,
                                     binding_sentence)
from analysis.plots.cost import unjudged_picks
from analysis.plots.ranks import RANK_KEYS
from analysis.plots.weak import SERIES_KEYS


# Shorter than this, a run measures the timer, thread start-up and the harness more than the code.
SHORT_RUN_S = 1e-3
# A harness costing more than this share of the runs' own time is worth a warning by itself.
OVERHEAD_WARNING = 0.10
# Median / min of the repetitions above this, in the typical configuration: the machine was busy.
BUSY_SPREAD = 1.10
# Fewer repetitions than this have no spread to judge and a minimum as noisy as one run.
MIN_REPETITIONS = 3


def harness_overhead(meta: dict) -> float | None:
    """The harness's time beyond its children's, as a share of theirs, over every session
    (psweep records each invocation in meta.json `sessions`); None when not recorded."""
    sessions = [s for s in meta.get("sessions") or [] if isinstance(s, dict)]
    try:
        sweep = sum(float(s["sweep_wall_s"]) for s in sessions)
        children = sum(float(s["children_process_s"]) for s in sessions)
        if children > 0:
            return (sweep - children) / children
    except (KeyError, TypeError, ValueError):
        pass
    shares = [s.get("overhead") for s in sessions if isinstance(s.get("overhead"), (int, float))]
    return max(shares) if shares else None


def measurement_section(results: Results, speedup: pd.DataFrame) -> str:
    """Warnings that the numbers below may not mean much: runs too short to time, a harness
    that cost a large share of the sweep, repetitions spread so widely the machine was busy."""
    warnings = []
    rated = speedup.dropna(subset=["wall_s_min"])
    overhead = harness_overhead(results.meta)
    overhead_text = (f" The harness itself cost {overhead:.0%} on top of the runs' own process "
                     f"time in this sweep (meta.json `sessions`)." if overhead is not None else "")
    short = rated[rated["wall_s_min"] < SHORT_RUN_S]
    if len(short):
        fastest = short["wall_s_min"].min()
        warnings.append(
            f"**Runs too short to measure well.** {len(short)} of {len(rated)} configurations "
            f"ran for under {SHORT_RUN_S * 1e3:g} ms (the shortest {fastest * 1e6:.0f} µs): at "
            f"that length timer resolution, thread start-up and the scheduler weigh as much as "
            f"the simulation.{overhead_text} Raise S (time units) or N ({advice.BASE_S}, "
            f"{advice.BASE_N}, or their lists under `sweep`) so that every run takes at least a "
            f"few milliseconds.")
    elif overhead is not None and overhead > OVERHEAD_WARNING:
        warnings.append(f"**High harness overhead.**{overhead_text} Runs this short are "
                        f"dominated by process start-up; lengthen them.")
    spread = (rated["wall_s_median"] / rated["wall_s_min"])[rated["reps"] >= MIN_REPETITIONS]
    if len(spread) and spread.median() > BUSY_SPREAD:
        worst = rated.loc[spread.idxmax()]
        keys = ["engine"] + [k for k in varying(rated, CONFIG_PARAMS + ["T"]) if k != "engine"]
        label = ", ".join(f"{SHORT.get(k, k)}={fmt(worst[k])}" for k in keys)
        warnings.append(
            f"**The machine was busy.** In the typical configuration the median repetition took "
            f"{spread.median():.2f}x the fastest (worst: {spread.max():.1f}x at {label}); on a "
            f"quiet machine repetitions agree within a few percent. Minima are still the best "
            f"estimate, but ratios between close configurations are not trustworthy: raise "
            f"{advice.REPETITIONS} or re-run on a quiet machine.")
    if not warnings:
        return ""
    return "\n## Measurement warnings\n\n" + "\n\n".join(warnings) + "\n"


def serial_caveats(config: pd.DataFrame, cores: int | None) -> str:
    """What makes one configuration's f and e mean less than they seem (`config`: its rows of the
    speed-up table, T=1 included): threads that made it slower, thread counts beyond the cores,
    too few repetitions behind the minima. '' when none."""
    def at(rows):
        return "T=" + ", ".join(fmt(t) for t in rows["T"])
    caveats = []
    slower = config[(config["T"] > 1) & (config["speedup"] < 1)]
    if len(slower):
        caveats.append(f"speed-up below 1 at {at(slower)}: no serial fraction explains "
                       f"that, f and e there measure overhead")
    beyond = config[config["T"] > cores] if cores else config.iloc[:0]
    if len(beyond):
        caveats.append(f"{at(beyond)} beyond the {cores} cores: e there is oversubscription "
                       f"(left out of f)")
    few = config[config["reps"] < MIN_REPETITIONS]
    if len(few):
        caveats.append(f"{int(few['reps'].min())} repetition(s) at {at(few)}: minima as noisy "
                       f"as one run; raise {advice.REPETITIONS} to {MIN_REPETITIONS} or more")
    return "; ".join(caveats)


def serial_section(speedup: pd.DataFrame, cores: int | None) -> str:
    """Per engine: Amdahl's f and the Karp-Flatt e at every T > 1, one row per configuration,
    with what makes them doubtful in the same row."""
    rated = speedup.dropna(subset=["karp_flatt"])
    if rated.empty:
        return ""
    fitted_on = f"the thread counts from 2 to the {cores} cores" if cores else "every thread count"
    text = ("\n## Serial fraction\n\n"
            "`Amdahl f` is the serial fraction that best explains the measured times (least "
            f"squares of t(T)/t(1) = f + (1-f)/T over {fitted_on}); `e at T` is the Karp-Flatt "
            "metric (1/speed-up - 1/T) / (1 - 1/T), the serial fraction that the speed-up at "
            "that T alone implies. Equal e across T: a fixed serial part, Amdahl's law holds. "
            "e rising with T: overhead that grows with the threads (synchronisation, "
            "imbalance); past the cores, oversubscription. Both are in speedup.csv "
            "(`karp_flatt`, `amdahl_f`, `amdahl_speedup`). A `caveat` says where they mean "
            "less: a speed-up below 1 (e above 1, which no serial fraction gives), thread "
            f"counts beyond the cores, fewer than {MIN_REPETITIONS} repetitions.\n")
    for engine, group in rated.groupby("engine", sort=True):
        keys = [c for c in varying(group, CONFIG_PARAMS) if c != "engine"]
        rows = []
        by = keys if len(keys) > 1 else (keys or ["engine"])[0]  # a scalar key for one column
        for key, config in group.groupby(by, dropna=False, sort=True):
            row = dict(zip(keys, key if isinstance(key, tuple) else (key,)))
            row["Amdahl f"] = config["amdahl_f"].iloc[0]
            row.update({f"e at T={fmt(t)}": e for t, e in zip(config["T"], config["karp_flatt"])})
            # With its T=1 row: the repetitions behind every speed-up count.
            every_t = speedup.merge(config[CONFIG_PARAMS].iloc[:1], on=CONFIG_PARAMS)
            row["caveat"] = serial_caveats(every_t, cores)
            rows.append(row)
        ts = [f"e at T={fmt(t)}" for t in sorted(group["T"].unique())]
        shown = pd.DataFrame(rows, columns=keys + ["Amdahl f"] + ts + ["caveat"])
        if not shown["caveat"].any():
            shown = shown.drop(columns="caveat")
        by = " and ".join(SHORT.get(k, k) for k in keys) or "configuration"
        text += f"\n### {engine}: serial fraction per {by}\n\n" + markdown_table(shown)
    return text


def cost_section(contests: pd.DataFrame) -> str:
    """Per scene and T: which engine was fastest and what the picking engine (auto) chose. A
    choice is judged only against its own engine swept beside it; where that engine was not
    swept, the row and a sentence say what to add to the config."""
    if contests.empty:
        return ""
    # N and T always: they are what the reader looks up, even when the sweep has one of each.
    keys = ["N", "T"] + [k for k in varying(contests, CONFIG_PARAMS)
                         if k in contests.columns and k != "N"]
    shown = contests[keys + ["engines", "fastest", "fastest_wall_s"]].rename(
        columns={"engines": "engines measured", "fastest_wall_s": "fastest wall s"})
    text = ("\n## Which engine wins where\n\n`ns_per_particle_step` in speedup.csv is the wall "
            "time divided by N × S × K (particle-steps): the cost of moving one particle "
            "through one sub-step, comparable across engines of any complexity (flat in N: "
            "O(N); growing with N: O(N²)); `ns_per_pair_test` divides by the pair tests "
            "instead. Per scene and thread count, the fastest of the measured engines")
    summary = ""
    if contests["picker"].notna().any():
        text += (", and what the engine that chooses by itself picked. `picked / fastest` above 1 "
                 "is the time lost by the choice; `no` where it chose another engine than the "
                 "fastest (on close timings that can be noise: compare the times)")
        judged = contests["picked_is_fastest"].map({True: "yes", False: "no"})
        judged = judged.where(contests["not_judged"] == "", "not judged: " + contests["not_judged"])
        shown = shown.assign(**{
            "picker": contests["picker"], "picked": contests["picked"],
            "picked fastest?": judged,
            "picked / fastest": contests["picked_wall_s"] / contests["fastest_wall_s"]})
        verdicts = contests["picked_is_fastest"].dropna()
        summary = (f"\n{int((verdicts == False).sum())} of {len(verdicts)} judged choices were "  # noqa: E712
                   f"not the fastest measured engine.\n" if len(verdicts) else "\n")
        missing = unjudged_picks(contests)
        if missing:
            count = int(((contests["not_judged"] != "") & contests["picked"].isin(missing)).sum())
            summary += (f"\n{count} choices cannot be judged: the engine picked "
                        f"({', '.join(missing)}) was not swept on its own at that scene and T. "
                        f"Add it to {advice.SWEEP_ENGINE} in the config to see whether the "
                        f"pick was the fastest.\n")
    return text + ":\n\n" + markdown_table(shown) + summary


def weak_section(weak: pd.DataFrame) -> str:
    if weak.empty:
        return ""
    keys = varying(weak, SERIES_KEYS) or ["engine"]
    growing = [c for c in ["L"] if weak[c].nunique() > 1]
    shown = weak[keys + ["T", "N"] + growing + ["wall_s_min", "weak_efficiency",
                                                "scaled_speedup", "gustafson_serial"]]
    shown = shown.rename(columns={"wall_s_min": "wall s", "weak_efficiency": "efficiency",
                                  "scaled_speedup": "scaled speed-up",
                                  "gustafson_serial": "Gustafson s"})
    return ("\n## Weak scaling\n\nThe problem grows with the threads (N ~ T for the O(N) "
            "engines, N ~ √T for brute's N² pairs), so ideally the time stays flat. "
            "`efficiency` = t(1) / t(T); `scaled speed-up` = T × efficiency, Gustafson's "
            "speed-up of the T-thread problem over one thread (ideal T); `Gustafson s` is the "
            "serial fraction of S = T - s(T - 1) fitted over T up to the cores. Also in "
            "weak.csv.\n\n" + markdown_table(shown))


def ranks_section(ranks: pd.DataFrame, weak: pd.DataFrame) -> str:
    """Runs on P ranks (ranks.py): strong scaling against P x T, the communication share, and
    weak scaling over P."""
    if ranks.empty:
        return ""
    keys = varying(ranks, RANK_KEYS) or ["engine"]
    shown = ranks[keys + ["N", "P", "T", "wall_s_min", "speedup_P", "efficiency_P", "comm_share",
                          "wait_share", "halo_per_rank"]].copy()
    shown = shown.loc[:, ~shown.columns.duplicated()]
    for column in ["comm_share", "wait_share"]:
        shown[column] = shown[column].map(lambda v: f"{v:.0%}" if pd.notna(v) else "")
    shown = shown.rename(columns={"wall_s_min": "wall s", "speedup_P": "speed-up",
                                  "efficiency_P": "efficiency", "comm_share": "in MPI",
                                  "wait_share": "waiting", "halo_per_rank": "halo per rank"})
    text = ("\n## Ranks\n\nOne simulation on P processes of T threads each (the mpi engine, "
            "docs/engines.md). `speed-up` = t(P=1, T=1) / t(P, T) of the same configuration, "
            "`efficiency` = speed-up / (P × T); `in MPI` is the slowest rank's seconds in MPI calls "
            "over the loop (comm_s_max / wall_s), `waiting` the part of it spent waiting for the "
            "last rank (wait_s_max), `halo per rank` the copies of other ranks' particles a rank "
            "holds per sub-step. Also in ranks.csv.\n\n" + markdown_table(shown))
    if not weak.empty:
        shown = weak[["T", "P", "N", "L", "wall_s_min", "weak_efficiency_P"]].rename(
            columns={"wall_s_min": "wall s", "weak_efficiency_P": "efficiency"})
        text += ("\n\n### Weak scaling over P\n\nN grows with P at a constant density, so "
                 "ideally the time stays flat: `efficiency` = t(P=1) / t(P).\n\n"
                 + markdown_table(shown))
    return text


def ceilings_section(speedup: pd.DataFrame, ceilings: Ceilings | None) -> str:
    """Each engine against this machine's ceilings (ceilings.py): one sentence per engine on the
    ceiling that binds it, then every configuration's share of each."""
    if ceilings is None:
        return ("\n## Against this machine's ceilings\n\nmeta.json holds no ceilings (a sweep "
                "older than them, or a build without the `ceilings` program): `make ceilings` "
                "measures them, and a new sweep records them.\n")
    rated = speedup.dropna(subset=["wall_s_min"])
    if rated.empty:
        return ""
    one, all_cpus = (1 / r for r in ceilings.pair_rate)
    load = f", measured at load average {ceilings.load}" if ceilings.load else ""
    text = ("\n## Against this machine's ceilings\n\nThe ceilings psweep recorded for this "
            f"machine and build (meta.json `ceilings`, docs/performance.md{load}; `make "
            f"ceilings` measures them afresh for the sweeps after it): the pair kernel's "
            f"peak {one:.3f} ns per pair test at T = 1 and {all_cpus:.3f} ns at T = "
            f"{ceilings.cpus} (a rate {ceilings.pair_rate[1] / ceilings.pair_rate[0]:.2f}x "
            f"T = 1's: the most a compute-bound loop can gain from threads here), memory "
            f"bandwidth {ceilings.bandwidth[0]:.1f} and {ceilings.bandwidth[1]:.1f} GB/s, a "
            f"process started in {ceilings.process_start_s * 1e3:.1f} ms. `% of pair peak`: "
            f"the "
            f"peak's time per pair test over the loop's; `% of bandwidth`: the time to move a "
            f"particle-step's {STATE_BYTES} bytes of state at that bandwidth over the loop's "
            f"time per particle-step; `loop % of process`: wall_s over the whole process; "
            f"`scaling / machine`: the speed-up over the kernel's own gain at that T (1: as "
            f"good as this machine allows); `builds / sub-step`: how often the broad phase "
            f"built its structure afresh (1: every sub-step). Also in speedup.csv.\n\n")
    for engine, rows in rated.groupby("engine", sort=True):
        text += f"- {binding_sentence(engine, rows, ceilings)}\n"
    keys = ["engine"] + [k for k in varying(rated, CONFIG_PARAMS) if k != "engine"] + ["T"]
    shown = rated[keys + CEILING_COLUMNS + ["builds_per_substep"]].rename(columns={
        "pair_peak_pct": "% of pair peak", "bandwidth_pct": "% of bandwidth",
        "loop_share_pct": "loop % of process", "scaling_vs_machine": "scaling / machine",
        "builds_per_substep": "builds / sub-step"})
    return text + "\n" + markdown_table(shown)
