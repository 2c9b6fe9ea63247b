"""Every CSV the analysis writes goes through write_csv, so they all read alike.

Floats keep full precision: pandas writes the shortest text that parses back to the same double
(Python's repr), so a number recomputed from runs.csv matches the CSV to the last bit instead of
to the 6 significant digits a %g format would keep. Integer-valued parameters print as integers
(N=1000, L=20000, not 1000.0, 20000.0); empty cells stay empty.
"""
from __future__ import annotations

import pandas as pd

INTEGER_COLUMNS = ["N", "L", "r", "S", "slow_factor", "G", "T", "reps", "reps_a", "reps_b", "failed"]


def write_csv(table: pd.DataFrame, path) -> None:
    out = table.copy()
    for column in INTEGER_COLUMNS:
        if column not in out.columns or not pd.api.types.is_numeric_dtype(out[column]):
            continue
        values = out[column].dropna()
        if (values == values.round()).all():
            out[column] = out[column].astype("Int64")
    out.to_csv(path, index=False)
