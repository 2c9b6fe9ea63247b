"""make regress: compare a run of the regression suite with the committed baseline.

Pure functions over measurement frames, tested on fixtures; running the suite is
suite.py, writing the report report.py. A measurement frame has one row per
recorded repetition with the columns in MEASUREMENT_COLUMNS: `part` is `instructions` (one
valgrind run per configuration: deterministic) or `wall` (psweep's repetitions on the real
machine: noisy); `metric` names what `value` holds (instructions, wall_s or process_s).

Three checks, reported apart because they mean different things:
- instructions gate at a small relative threshold where the baseline was counted in the same
  environment: the same instruction set (make regress builds for x86-64-v3 and pins glibc's CPU
  dispatch, so the count is the code's on any such CPU; a -march=native build's count is the
  CPU's as well, and gates only on the same CPU model and ISA flags), compiler and valgrind;
- wall time against the baseline gates only on the machine that recorded it (its
  /etc/machine-id), running at its speed (the suite's median change within 10%), when the
  change of the minimum is beyond max(5%, 3 MADs) *and* the Mann-Whitney U test finds the two
  samples different; against a base commit measured here in rounds (make regress BASE=REF) it
  gates on any machine, when the median of the rounds' head/base ratios is beyond 5% *and* the
  Wilcoxon signed-rank test finds the ratios shifted;
- state hashes must equal the baseline's everywhere: a changed hash is a changed result, a
  correctness regression, whatever the speed.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pandas as pd

from analysis.common.stats import compare_samples

MEASUREMENT_COLUMNS = ["part", "group", "config_id", "label", "engine", "engine_ran", "T",
                       "rep", "status", "metric", "value", "state_hash", "error"]
PARTS = ("instructions", "wall")

# What has to match for a comparison to gate. Build flags are deliberately absent: a build with
# other flags (-O1) is exactly what the instruction gate must catch.
ENVIRONMENT_KEYS = {
    "instructions": ("isa", "compiler", "valgrind", "glibc_tunables"),
    "wall": ("machine_id", "cpu_model", "online_cpus", "physical_cores"),
}


@dataclass(frozen=True)
class Thresholds:
    instructions: float = 0.01  # relative; measured spread of repeated counts is < 1e-4
    wall_rel: float = 0.05      # relative change of the minimum that may count at all
    wall_mads: float = 3.0      # ... and it must exceed this many median absolute deviations
    alpha: float = 0.05         # two-sided significance level (U test, signed-rank test)
    machine_speed: float = 0.10  # the suite's median wall change that means another machine


@dataclass
class Comparison:
    """One row of the table: a configuration's metric against its baseline."""
    part: str
    label: str
    config_id: str
    metric: str
    baseline: float | None
    now: float | None
    change: float | None   # now / baseline - 1
    verdict: str           # ok, regressed, improved, new, failed, not measured
    gated: bool            # False: reported only (other machine, or not measurable here)
    detail: str = ""       # threshold, p-value, or why it is not gated

    @property
    def fails(self) -> bool:
        return self.gated and self.verdict in ("regressed", "failed")


@dataclass
class HashCheck:
    """A configuration whose final state differs from the baseline's, or between repetitions."""
    part: str
    label: str
    config_id: str
    baseline: str
    now: str
    verdict: str  # changed, nondeterministic


def isa(meta: dict) -> dict:
    """The instruction set a build's code uses: its -march level, or for -march=native the CPU
    (model and ISA flags) it was built on."""
    machine = meta.get("machine", {})
    march = re.search(r"-march=(\S+)", meta.get("build", {}).get("flags") or "")
    level = march.group(1) if march else None
    if level and level != "native":
        return {"level": level}
    return {"level": level, "cpu_model": machine.get("cpu_model"),
            "isa_flags": machine.get("isa_flags")}


def environment(meta: dict) -> dict:
    """The facts of a run's meta.json that decide whether its numbers compare with another's."""
    machine = meta.get("machine", {})
    return {"machine_id": machine.get("machine_id"), "cpu_model": machine.get("cpu_model"),
            "isa": isa(meta),
            "online_cpus": machine.get("online_cpus"),
            "physical_cores": machine.get("physical_cores"),
            "compiler": meta.get("build", {}).get("compiler"), "valgrind": meta.get("valgrind"),
            "glibc_tunables": meta.get("glibc_tunables")}


def environment_differences(baseline_meta: dict, now_meta: dict, part: str) -> list[str]:
    """Why `part` must not gate: one phrase per fact that differs (empty: it gates)."""
    base, now = environment(baseline_meta), environment(now_meta)
    reasons = []
    for key in ENVIRONMENT_KEYS[part]:
        if base[key] == now[key]:
            continue
        if key == "isa" and base[key]["level"] != now[key]["level"]:
            reasons.append(f"instruction set differs (baseline -march={base[key]['level']}, "
                           f"here -march={now[key]['level']})")
        elif key == "isa" and base[key].get("cpu_model") != now[key].get("cpu_model"):
            reasons.append(f"-march=native on another CPU (baseline "
                           f"{base[key].get('cpu_model')!r}, here {now[key].get('cpu_model')!r})")
        elif key == "machine_id":
            reasons.append("another machine (its /etc/machine-id differs from the baseline's"
                           + (")" if base[key] else ", which the baseline does not record)"))
        elif key == "isa":
            only_base = sorted(set(base[key]["isa_flags"] or []) - set(now[key]["isa_flags"] or []))
            only_now = sorted(set(now[key]["isa_flags"] or []) - set(base[key]["isa_flags"] or []))
            reasons.append(f"-march=native with other ISA flags (baseline only: "
                           f"{' '.join(only_base) or '-'}; here only: {' '.join(only_now) or '-'})")
        else:
            reasons.append(f"{key} differs (baseline {base[key]!r}, here {now[key]!r})")
    return reasons


def least(frame: pd.DataFrame, by: str) -> pd.Series:
    """The least `value` of the successful runs per `by` (noise only adds time)."""
    ok = frame[frame["status"] == "ok"]
    return ok.assign(value=ok["value"].astype(float)).groupby(by)["value"].min()


def speed_difference(baseline: pd.DataFrame, now: pd.DataFrame, th: Thresholds) -> list[str]:
    """Why the wall part must not gate against a stored baseline although the environment looks
    the same: the suite as a whole runs at another speed here (the median over its configurations
    of the change of the minimum beyond machine_speed). VMs of one model name and core count
    differ by 2x, and one VM by 40% from one hour to the next: a stored wall time only compares
    on a machine running at the baseline's speed. A slowdown of the code everywhere looks the same
    and is left to the instruction counts and to make regress BASE=REF."""
    def wall(frame):
        return least(frame[frame["part"] == "wall"], "config_id")
    ratios = (wall(now) / wall(baseline)).dropna()
    if ratios.empty:
        return []
    change = float(np.median(ratios)) - 1
    if abs(change) <= th.machine_speed:
        return []
    return [f"the suite runs {change:+.0%} against the baseline here (median of {len(ratios)} "
            f"configurations): another machine's speed, or this one's at another time; "
            f"compare with make regress BASE=REF"]


def mad(values) -> float:
    values = np.asarray(values, dtype=float)
    return float(np.median(np.abs(values - np.median(values)))) if values.size else 0.0


def wall_verdict(baseline, now, th: Thresholds) -> tuple[str, float, str]:
    """(verdict, change of the minimum, detail) for two samples of repeated wall times.

    The minimum is the statistic of record (noise only adds time). Its change counts when it is
    beyond max(wall_rel, wall_mads x the larger relative MAD of the two) and the U test
    rejects "same distribution" at alpha; either alone is not enough: a 6% step on a noisy
    configuration can be all noise, and a significant 1% shift is below what a shared machine
    can be trusted with."""
    baseline, now = np.asarray(baseline, float), np.asarray(now, float)
    base_min = baseline.min()
    change = now.min() / base_min - 1
    # Each sample's spread relative to its own level: a build 5x slower and noisy under load has
    # a large MAD in seconds, which must not hide the 5x.
    spread = max(mad(baseline) / np.median(baseline), mad(now) / np.median(now))
    threshold = max(th.wall_rel, th.wall_mads * spread)
    test, p, direction = compare_samples(baseline, now, th.alpha)  # make compare's U test
    detail = f"threshold {threshold:.1%}, {test} p={p:.3g}"
    if abs(change) <= threshold or direction not in ("slower", "faster"):
        return "ok", change, detail
    # The minimum and the medians (the test's direction) must agree on the sign.
    if (change > 0) != (direction == "slower"):
        return "ok", change, detail + f", but the samples are {direction}"
    return ("regressed" if change > 0 else "improved"), change, detail


def paired_wall_verdict(base, head, th: Thresholds) -> tuple[str, float, str]:
    """(verdict, change, detail) for one configuration measured in rounds, base[r] and head[r]
    each the least of a round's runs, seconds apart (make regress BASE=REF). What the machine does
    to a round falls on both, so the round's ratio head/base cancels it where the minima of two
    samples cannot: the change is the median ratio, and it counts when beyond wall_rel and the
    Wilcoxon signed-rank test of the log ratios rejects "no shift" at alpha. The MAD rule of
    wall_verdict is left out: it bounds one run's noise, and the median of the rounds varies far
    less."""
    from scipy.stats import wilcoxon
    log_ratios = np.log(np.asarray(head, float) / np.asarray(base, float))
    change = float(np.expm1(np.median(log_ratios)))
    p = float(wilcoxon(log_ratios).pvalue) if np.any(log_ratios != 0) else 1.0
    detail = (f"median of {len(log_ratios)} rounds' ratios, threshold {th.wall_rel:.1%}, "
              f"signed-rank p={p:.3g}")
    if abs(change) <= th.wall_rel or p >= th.alpha:
        return "ok", change, detail
    return ("regressed" if change > 0 else "improved"), change, detail


def instruction_verdict(baseline: float, now: float, th: Thresholds) -> tuple[str, float]:
    change = now / baseline - 1
    if abs(change) <= th.instructions:
        return "ok", change
    return ("regressed" if change > 0 else "improved"), change


def _by_config(frame: pd.DataFrame, part: str) -> dict:
    return {cid: rows for cid, rows in frame[frame["part"] == part].groupby("config_id", sort=False)}


def compare_part(baseline: pd.DataFrame, now: pd.DataFrame, part: str, th: Thresholds,
                 not_gated_because: list[str], paired: bool = False) -> list[Comparison]:
    """Every configuration of `part` in this run against the baseline's. Configurations only in
    the baseline are left out: the suite changed, and the report lists the new ones as `new`.
    `paired`: `rep` numbers rounds in which both ran (make regress BASE=REF)."""
    gated = not not_gated_because
    why = "; ".join(not_gated_because)
    base_rows = _by_config(baseline, part)
    out = []
    for config_id, rows in _by_config(now, part).items():
        label, metric = rows["label"].iloc[0], rows["metric"].iloc[0]
        ok = rows[rows["status"] == "ok"]["value"].astype(float)
        base = base_rows.get(config_id)
        base_ok = (base[base["status"] == "ok"]["value"].astype(float)
                   if base is not None else pd.Series(dtype=float))
        row = Comparison(part, label, config_id, metric, None, None, None, "ok", gated, why)
        if ok.empty:
            errors = rows["error"].dropna().astype(str)
            reason = errors.iloc[0].strip().splitlines()[-1] if not errors.empty else "no ok run"
            # A run that cannot be measured here (valgrind on an ISA it does not know) is not a
            # regression of the code when the environment differs anyway.
            row.verdict = "failed" if gated else "not measured"
            row.detail = f"{len(rows)} run(s) not ok: {reason}" + (f"; {why}" if why else "")
        elif base_ok.empty:
            row.now, row.verdict, row.gated = float(ok.median()), "new", False
            row.detail = "no baseline for this configuration"
        elif part == "instructions":
            row.baseline, row.now = float(base_ok.median()), float(ok.median())
            row.verdict, row.change = instruction_verdict(row.baseline, row.now, th)
            row.detail = f"threshold {th.instructions:.1%}" + (f"; {why}" if why else "")
        elif paired:
            rounds = pd.concat([least(base, "rep"), least(rows, "rep")], axis=1,
                               keys=["base", "head"]).dropna()
            row.baseline, row.now = float(base_ok.min()), float(ok.min())
            row.verdict, row.change, row.detail = paired_wall_verdict(rounds["base"],
                                                                      rounds["head"], th)
        else:
            row.baseline, row.now = float(base_ok.min()), float(ok.min())
            row.verdict, row.change, detail = wall_verdict(base_ok, ok, th)
            row.detail = detail + (f"; {why}" if why else "")
        out.append(row)
    return out


def check_hashes(baseline: pd.DataFrame, now: pd.DataFrame) -> list[HashCheck]:
    """Final-state hashes against the baseline's, for every configuration both have; runs of
    one configuration that disagree with each other are a failure of their own (determinism)."""
    base_hash = {}
    for (part, cid), rows in baseline[baseline["status"] == "ok"].groupby(["part", "config_id"]):
        base_hash[(part, cid)] = ";".join(sorted(set(rows["state_hash"].dropna().astype(str))))
    problems = []
    for (part, cid), rows in now[now["status"] == "ok"].groupby(["part", "config_id"], sort=False):
        hashes = sorted(set(rows["state_hash"].dropna().astype(str)))
        label, joined = rows["label"].iloc[0], ";".join(hashes)
        if len(hashes) > 1:
            problems.append(HashCheck(part, label, cid, base_hash.get((part, cid), ""), joined,
                                      "nondeterministic"))
        elif (part, cid) in base_hash and base_hash[(part, cid)] != joined:
            problems.append(HashCheck(part, label, cid, base_hash[(part, cid)], joined, "changed"))
    return problems


def outcome(comparisons: list[Comparison], hashes: list[HashCheck]) -> tuple[int, list[str]]:
    """Exit status (0 nothing regressed, 1 something did) and one line per reason."""
    reasons = [f"{c.label}: {c.metric} {c.verdict}"
               + (f" by {c.change:+.1%}" if c.change is not None else f" ({c.detail})")
               for c in comparisons if c.fails]
    reasons += [f"{h.label}: final state {h.verdict} ({h.part} run; baseline {h.baseline or '-'}, "
                f"now {h.now})" for h in hashes]
    return (1 if reasons else 0), reasons


def instruction_spread(measurements: pd.DataFrame) -> pd.DataFrame:
    """Per configuration, (max - min) / min of repeated instruction counts: the noise the
    instruction threshold has to stand above."""
    ok = measurements[(measurements["part"] == "instructions") & (measurements["status"] == "ok")]
    grouped = ok.groupby(["config_id", "label"], sort=False)["value"]
    table = grouped.agg(["min", "max", "count"]).reset_index()
    table["spread"] = table["max"] / table["min"] - 1
    return table
