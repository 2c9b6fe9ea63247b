"""Markdown tables for report.md and compare.md: one cell format for every table."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from analysis.common.labels import SHORT, fmt


def cell(value) -> str:
    """Three significant digits (enough to compare timings on a noisy machine), never
    scientific notation for the magnitudes a sweep produces, '-' for empty."""
    if isinstance(value, (float, np.floating)):
        if math.isnan(value):
            return "-"
        if value.is_integer() or abs(value) >= 100:
            return f"{value:.0f}"
        return f"{value:.3g}"
    return fmt(value)


def table_cell(value) -> str:
    """cell(), made safe inside a table row: a '|' or a line break in a program's message would
    end the cell or the row."""
    return cell(value).replace("|", "\\|").replace("\n", " ").replace("\r", " ")


def markdown_table(frame: pd.DataFrame) -> str:
    if frame.empty:
        return "_(none)_\n"
    header = "| " + " | ".join(SHORT.get(c, c) for c in frame.columns) + " |"
    rule = "|" + "|".join("---:" if pd.api.types.is_numeric_dtype(frame[c]) else "---"
                          for c in frame.columns) + "|"
    lines = [header, rule]
    lines += ["| " + " | ".join(table_cell(v) for v in row) + " |"
              for row in frame.itertuples(index=False)]
    return "\n".join(lines) + "\n"
