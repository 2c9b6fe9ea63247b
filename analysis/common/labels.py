"""Parameter names and number formats shared by every table, plot title and legend, so a value
reads the same in report.md, compare.md and a figure."""
from __future__ import annotations

import math

import numpy as np

UNITS = {"N": "particles", "L": "box side", "r": "radius", "S": "time units",
         "slow_factor": "sub-steps per time unit", "G": "cells per side", "T": "threads"}
SHORT = {"slow_factor": "K"}


def fmt(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, (int, float, np.integer, np.floating)):
        return str(int(value)) if float(value).is_integer() else f"{value:g}"
    return str(value)


def picked(engine_ran: str) -> str:
    """The engine a run ran: psim records a picking engine's choice as "auto:<engine>"."""
    return engine_ran.split(":")[-1]


def engine_name(rows) -> str:
    """The engine of `rows` (one engine), with what it ran when it picks another per scene:
    "auto (ran grid, sweep)". A plot titled "engine=auto" must say which engine's time it
    shows."""
    engine = str(rows["engine"].iloc[0])
    ran = rows["engine_ran"].dropna().astype(str) if "engine_ran" in rows else []
    picks = sorted({picked(r) for r in ran} - {engine})
    return f"{engine} (ran {', '.join(picks)})" if picks else engine


def series_label(row, columns) -> str:
    return ", ".join(f"{SHORT.get(c, c)}={fmt(row[c])}" for c in columns) or "all runs"


def axis_label(param: str) -> str:
    name = SHORT.get(param, param)
    return f"{name} ({UNITS[param]})" if param in UNITS else name
