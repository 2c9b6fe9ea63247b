"""How a speed test's points follow from its times: the grade config's `timing.curve` and
`timing.quiet` (docs/programs.md, "The speed points").

The curve is logarithmic in the time against the reference's: full points at or below
`full_at` times the reference's time, none at or above `zero_at` times it, and between, the
share of that span (in log time) left to go. Logarithmic because a speed-up is a ratio: halving
a time is worth as much at 4 s as at 1 s, and a program 3 times faster than another earns the
same points more wherever the two lie in the span.

At a T above the timing's smallest, the time alone would pay a program for being fast at one
thread and idling the others; the points are the curve's times the share of the program's own
speed-up over its time at the smallest T, none at a speed-up of 1 or less, all at
`speedup_full_at` of the ideal one (the ratio of the thread counts), logarithmic between.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass

from analysis.common.load import InputError

CURVE_KEYS = {"full_at", "zero_at", "speedup_full_at"}
QUIET_KEYS = {"wait_s", "busy_runs"}
BUSY_RUNS = ("exclude", "count")


@dataclass(frozen=True)
class SpeedCurve:
    # At or below this share of the reference's time, full points: 0.25, 4 times its speed, is
    # what a tuned all-pairs or a broad phase reaches on the timing scene, not a plain program.
    full_at: float = 0.25
    # At or above this multiple of the reference's time, none.
    zero_at: float = 4.0
    # The parallel efficiency (own speed-up / the ratio of thread counts) that earns a T above
    # the smallest all of its speed-up share.
    speedup_full_at: float = 0.75

    def time_share(self, ratio: float) -> float:
        """The share of a test's points at `ratio` = the submission's time / the reference's."""
        if ratio <= self.full_at:
            return 1.0
        if ratio >= self.zero_at:
            return 0.0
        return math.log(self.zero_at / ratio) / math.log(self.zero_at / self.full_at)

    def speedup_share(self, speedup: float, ideal: float) -> float:
        """The share kept at a T whose own speed-up over the smallest T is `speedup`, `ideal`
        being the ratio of the two thread counts: 0 at a speed-up of 1 or less (idle threads
        earn nothing), 1 from speedup_full_at x ideal on."""
        full = self.speedup_full_at * ideal
        if speedup <= 1:
            return 0.0
        if speedup >= full or full <= 1:
            return 1.0
        return math.log(speedup) / math.log(full)


@dataclass(frozen=True)
class Quiet:
    # How long psweep waits before each timed run for the machine to be as quiet as when the
    # sweep began (psweep's quiet_wait_s): a few seconds marks busy runs, minutes waits them out.
    wait_s: float = 2.0
    # What a run still busy after the wait counts for: "exclude", shown in the report and
    # worth no points; "count", its time taken as any other's.
    busy_runs: str = "exclude"


def _number(section: dict, key: str, where: str, default: float, what: str) -> float:
    value = section.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0 \
            or math.isinf(value):
        raise InputError(f"{where}.{key}: expected {what}, got {json.dumps(value)}")
    return float(value)


def _section(timing: dict, key: str, allowed: set[str], where: str) -> dict:
    section = timing.get(key, {})
    if not isinstance(section, dict):
        raise InputError(f"{where}.{key}: expected an object with keys among "
                         f"{', '.join(sorted(allowed))}")
    unknown = sorted(set(section) - allowed)
    if unknown:
        raise InputError(f"{where}.{key}.{unknown[0]}: unknown key (expected one of "
                         f"{', '.join(sorted(allowed))})")
    return section


def read_curve(timing: dict, where: str) -> SpeedCurve:
    """timing.curve of the grade config, `where` naming the timing section in messages."""
    raw = _section(timing, "curve", CURVE_KEYS, where)
    default = SpeedCurve()
    where = f"{where}.curve"
    full_at = _number(raw, "full_at", where, default.full_at,
                      "a share of the reference's time > 0 (0.25: full points at 4 times its "
                      "speed)")
    zero_at = _number(raw, "zero_at", where, default.zero_at,
                      "a multiple of the reference's time > full_at (4: no points at a "
                      "quarter of its speed)")
    if zero_at <= full_at:
        raise InputError(f"{where}.zero_at: expected more than full_at ({full_at:g}), got "
                         f"{zero_at:g}")
    efficiency = _number(raw, "speedup_full_at", where, default.speedup_full_at,
                         "a parallel efficiency > 0 and <= 1 (0.75: a T's speed-up share in "
                         "full at 0.75 x T over T = 1)")
    if efficiency > 1:
        raise InputError(f"{where}.speedup_full_at: expected a parallel efficiency > 0 and "
                         f"<= 1, got {efficiency:g}")
    return SpeedCurve(full_at, zero_at, efficiency)


def read_quiet(timing: dict, where: str) -> Quiet:
    """timing.quiet of the grade config."""
    raw = _section(timing, "quiet", QUIET_KEYS, where)
    where = f"{where}.quiet"
    wait = raw.get("wait_s", Quiet.wait_s)
    if isinstance(wait, bool) or not isinstance(wait, (int, float)) or not 0 <= wait <= 3600:
        raise InputError(f"{where}.wait_s: expected seconds from 0 to 3600 that psweep waits "
                         f"for quiet before each timed run, got {json.dumps(wait)}")
    busy = raw.get("busy_runs", Quiet.busy_runs)
    if busy not in BUSY_RUNS:
        raise InputError(f"{where}.busy_runs: expected one of {', '.join(BUSY_RUNS)}, got "
                         f"{json.dumps(busy)}")
    return Quiet(float(wait), busy)
