"""Each configuration against this machine's ceilings (meta.json's `ceilings`, measured by the
`ceilings` program of the sweep's build: docs/performance.md, "The machine's ceilings").

  pair_peak_pct       the pair kernel's peak ns per pair test at T / ns_per_pair_test (the whole
                      loop's time per pair test), in percent: 100 is a loop that does nothing
                      but pair tests at the machine's best rate
  bandwidth_pct       the time the triad's bandwidth at T needs to move a particle-step's state
                      (STATE_BYTES: x, y, ux, uy read, x, y written) / ns_per_particle_step, in
                      percent: 100 is a loop bound by memory
  loop_share_pct      wall_s_min / process_s_min: the loop's share of the whole process (the rest:
                      start-up, input, output)
  scaling_vs_machine  speedup / the kernel's own rate at T over its rate at T = 1: 1 scales as
                      well as this machine lets a compute-bound loop scale (on a VM whose vCPUs
                      share a core that ceiling is about 1.35x, not T)

A T between 1 and all CPUs takes the rates in between, linearly; beyond all CPUs those of all
CPUs. The figures are the ceilings' best repetitions (min ns, max GB/s), as every time here is
a minimum. Without ceilings in meta.json (an older sweep) the columns are empty.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from analysis.common.stats import RUN_KEYS, aggregate

CEILING_COLUMNS = ["pair_peak_pct", "bandwidth_pct", "loop_share_pct", "scaling_vs_machine"]
# A particle-step's own state: four doubles read (position, displacement), two written.
STATE_BYTES = 48
# From this share of a ceiling on, it is the one that binds.
BINDS_PCT = 50


@dataclass(frozen=True)
class Ceilings:
    cpus: int
    pair_rate: tuple[float, float]      # pair tests per ns at T = 1 and at all CPUs
    bandwidth: tuple[float, float]      # triad GB/s (bytes per ns) at T = 1 and at all CPUs
    process_start_s: float
    team_start_s: float
    load: str = ""                      # /proc/loadavg's 1-minute figure as they were measured

    @staticmethod
    def from_meta(meta: dict) -> "Ceilings | None":
        c = meta.get("ceilings")
        try:
            kernel, triad = c["pair_kernel"], c["bandwidth"]["triad"]
            return Ceilings(
                cpus=int(c["cpus"]),
                pair_rate=tuple(1 / kernel[t]["ns_per_pair_test"]["min"] for t in ("T1", "Tall")),
                bandwidth=tuple(triad[t]["gb_per_s"]["max"] for t in ("T1", "Tall")),
                process_start_s=c["startup"]["process_s"]["min"],
                team_start_s=c["startup"]["omp_team_s"]["min"],
                load=str(c.get("loadavg_before", "")).split(" ")[0])
        except (KeyError, TypeError, ValueError, ZeroDivisionError):
            return None

    def at(self, pair: tuple[float, float], threads) -> np.ndarray:
        """A T = 1 / all-CPU pair of rates at each T: linear in between, flat beyond."""
        t = np.asarray(threads, dtype=float)
        share = np.clip((t - 1) / max(self.cpus - 1, 1), 0, 1) if self.cpus > 1 else 0 * t
        return pair[0] + (pair[1] - pair[0]) * share

    def kernel_ratio(self, threads) -> np.ndarray:
        return self.at(self.pair_rate, threads) / self.pair_rate[0]


def add_ceilings(table: pd.DataFrame, runs: pd.DataFrame,
                 ceilings: Ceilings | None) -> pd.DataFrame:
    """`table` (speedup.csv's rows, with ns_per_pair_test, ns_per_particle_step and speedup) with
    CEILING_COLUMNS."""
    out = table.copy()
    if ceilings is None:
        for column in CEILING_COLUMNS:
            out[column] = np.nan
        return out
    peak_ns = 1 / ceilings.at(ceilings.pair_rate, out["T"])
    out["pair_peak_pct"] = 100 * peak_ns / out["ns_per_pair_test"]
    floor_ns = STATE_BYTES / ceilings.at(ceilings.bandwidth, out["T"])
    out["bandwidth_pct"] = 100 * floor_ns / out["ns_per_particle_step"]
    if "process_s" in runs.columns:
        process = aggregate(runs, "process_s")[RUN_KEYS + ["process_s_min"]]
        merged = out[RUN_KEYS].merge(process, on=RUN_KEYS, how="left")
        out["loop_share_pct"] = 100 * out["wall_s_min"].values / merged["process_s_min"].values
    else:
        out["loop_share_pct"] = np.nan
    out["scaling_vs_machine"] = out["speedup"] / ceilings.kernel_ratio(out["T"])
    return out


def binding_sentence(engine: str, rows: pd.DataFrame, ceilings: Ceilings) -> str:
    """Which ceiling binds `engine`, from its largest configuration at T = 1 (the longest
    wall_s_min) and the same configuration at its largest T up to all CPUs."""
    ones = rows[(rows["T"] == 1) & rows["wall_s_min"].notna()]
    if ones.empty:
        return f"**{engine}**: no T = 1 run to set against the ceilings."
    one = ones.loc[ones["wall_s_min"].idxmax()]
    where = f"at N = {int(one['N'])}" if pd.notna(one.get("N")) else ""
    shares = {"the pair kernel's peak": one["pair_peak_pct"],
              "memory bandwidth": one["bandwidth_pct"]}
    shares = {k: v for k, v in shares.items() if pd.notna(v)}
    loop = one["loop_share_pct"]
    if shares and max(shares.values()) >= BINDS_PCT:
        name = max(shares, key=shares.get)
        text = f"**{engine}** {where} is bound by {name}: {shares[name]:.0f}% of it at T = 1"
    elif pd.notna(loop) and loop < BINDS_PCT:
        text = (f"**{engine}** {where} is bound by start-up and I/O: its loop is {loop:.0f}% of "
                f"the process (an empty process starts in {ceilings.process_start_s * 1e3:.1f} "
                f"ms, an OpenMP team in {ceilings.team_start_s * 1e3:.2f} ms here)")
    else:
        best = ", ".join(f"{v:.0f}% of {k}" for k, v in shares.items()) or "no figure"
        text = (f"**{engine}** {where} is bound by no ceiling measured here ({best} at T = 1): "
                f"its time goes to the work around the pair tests (broad phase, order, resolve, "
                f"advance), the largest gap left")
    excess = one.get("tests_per_needed_pair")
    if pd.notna(excess):
        text += (f"; its broad phase leaves {excess:.3g} pair tests for each pair the scene "
                 f"needed (one that could collide in its sub-step)")
    builds = one.get("builds_per_substep")
    if pd.notna(builds) and builds > 0:
        text += f" and builds its structure afresh in {builds:.0%} of the sub-steps"
    scaled = rows[(rows["T"] > 1) & (rows["T"] <= ceilings.cpus)
                  & rows["scaling_vs_machine"].notna()]
    same = scaled[(scaled["N"] == one["N"])] if "N" in scaled else scaled
    if len(same):
        top = same.loc[same["T"].idxmax()]
        ratio = float(ceilings.kernel_ratio(top["T"]))
        text += (f"; T = {int(top['T'])} gives {top['speedup']:.2f}x, "
                 f"{top['scaling_vs_machine']:.0%} of the {ratio:.2f}x this machine's pair kernel "
                 f"itself gains from T = 1 to {int(top['T'])}")
        if ratio < 0.75 * top["T"]:
            text += (" (this machine's own ceiling for T is far below T: its CPUs share a core's "
                     "vector units, or other work took them while it was measured; judge scaling "
                     "against it, not against T)")
    return text + "."
