"""What each plotted point is, for report.html's tooltips.

A drawing function tags the points it plots with one line of text each (the configuration:
engine, N, T, ... and the engine auto ran); the value is added from the axis it is read on (its
label and the point's y), so a tooltip says what the reader sees. When the figure is saved,
figures.save() writes <stem>.points.json beside the PNG: every point's position as a fraction of the figure's width and
height (from the top left), and its text. Positions are taken after layout, in the figure's own
pixels, so they hold for the PNG at any display size; the page lays invisible hover targets over
the picture at those fractions. The PNG and SVG are unchanged: report.md does not need this.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from analysis.common.labels import SHORT, fmt, picked

_TAGS = "_hover_tags"  # the figure attribute holding (axes, xs, ys, texts, value axis)

# The parameters that say which configuration a point is, in the order a reader scans them.
CONFIG_KEYS = ["engine", "engine_ran", "N", "L", "r", "S", "slow_factor", "G", "T", "pin",
               "seed", "scene_file", "speed_min", "speed_max"]


def describe(row) -> str:
    """One point's configuration as "engine=auto (ran sweep), N=2000, T=2": the keys of
    CONFIG_KEYS that `row` has and that are set."""
    parts = []
    for key in CONFIG_KEYS:
        if key not in row.index or key == "engine_ran" or pd.isna(row[key]):
            continue
        text = f"{SHORT.get(key, key)}={fmt(row[key])}"
        ran = row.get("engine_ran") if key == "engine" else None
        if isinstance(ran, str) and ran and picked(ran) != row[key]:
            text += f" (ran {picked(ran)})"
        parts.append(text)
    return ", ".join(parts)


def tag(ax, xs, ys, texts, value: str = "y") -> None:
    """Remembers that the points (xs[i], ys[i]) drawn on `ax` are texts[i]; `value` names the
    axis their value is read on ("x" for horizontal bars)."""
    xs, ys = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
    texts = [str(t) for t in texts]
    if not (len(xs) == len(ys) == len(texts)):
        raise ValueError(f"hover.tag: {len(xs)} x, {len(ys)} y and {len(texts)} texts")
    tags = getattr(ax.figure, _TAGS, None)
    if tags is None:
        tags = []
        setattr(ax.figure, _TAGS, tags)
    tags.append((ax, xs, ys, texts, value))


def tag_rows(ax, xs, ys, rows: pd.DataFrame, value: str = "y") -> None:
    """The points (xs[i], ys[i]) just drawn on `ax` are the configurations of rows' i-th row."""
    tag(ax, xs, ys, [describe(row) for _, row in rows.iterrows()], value)


def positions(fig) -> list[dict]:
    """Every tagged point inside its axes, as fractions of the figure from the top left. Points
    drawn on one spot (every series' speed-up of 1 at T=1) become one target naming them all:
    otherwise only the topmost could ever be hovered."""
    width, height = fig.bbox.width, fig.bbox.height
    spots: dict[tuple, dict] = {}
    for ax, xs, ys, texts, value in getattr(fig, _TAGS, []):
        box = ax.bbox
        label = ax.get_ylabel() if value == "y" else ax.get_xlabel()
        what = label.removesuffix(", log scale") or "value"
        values = ys if value == "y" else xs
        for (px, py), v, text in zip(ax.transData.transform(np.column_stack([xs, ys])), values,
                                     texts):
            if not (math.isfinite(px) and math.isfinite(py)) or not box.contains(px, py):
                continue  # off the axes (a log axis cut it, or a NaN): nothing to hover
            line = f"{text}; {what}: {v:.4g}" if text else f"{what}: {v:.4g}"
            spot = spots.setdefault((round(px), round(py)), {
                "x": round(px / width, 5), "y": round(1 - py / height, 5), "text": ""})
            spot["text"] = f"{spot['text']}\n{line}" if spot["text"] else line
    return list(spots.values())


def write_positions(fig, png: Path) -> None:
    """<stem>.points.json beside the PNG, or no file (and an old one removed) when nothing was
    tagged."""
    path = png.with_suffix(".points.json")
    points = positions(fig)
    if points:
        path.write_text(json.dumps(points, separators=(",", ":")))
    else:
        path.unlink(missing_ok=True)


def read_positions(png: Path) -> list[dict]:
    path = png.with_suffix(".points.json")
    return json.loads(path.read_text()) if path.exists() else []
